// cairn_graph_slam::SlamNode in a container: scans, odometry and the base->laser TF of a simulated run (sim core,
// seeded) arrive over DDS from another context; the map must come back (transient local, so a late subscriber gets
// it), pose and map->odom TF follow each scan, the state can be saved and loaded, a broken state file gives a clear
// error without stopping the node, and malformed scans are skipped.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "cairn/sim/simulator.hpp"
#include "cairn/sim/world.hpp"
#include "cairn/msg_conversions.hpp"
#include "cairn/test_support.hpp"
#include "cairn_slam_msgs/msg/SlamGraph.hpp"
#include "cairn_slam_msgs/srv/LoadState.hpp"
#include "cairn_slam_msgs/srv/Optimize.hpp"
#include "cairn_slam_msgs/srv/SaveState.hpp"
#include "geometry_msgs/msg/PoseWithCovarianceStamped.hpp"
#include "nav_msgs/msg/OccupancyGrid.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using cairn::testing::wait_for;

namespace {

builtin_interfaces::msg::Time stampOf(double s) { return cairn::time_from_seconds(s); }

sensor_msgs::msg::LaserScan toMsg(const cairn::sim::LaserScan& s) {
  sensor_msgs::msg::LaserScan m;
  m.header.stamp = stampOf(s.stamp);
  m.header.frame_id = "laser";
  m.angle_min = s.angle_min;
  m.angle_max = s.angle_max;
  m.angle_increment = s.angle_increment;
  m.range_min = s.range_min;
  m.range_max = s.range_max;
  m.ranges = s.ranges;
  return m;
}

nav_msgs::msg::Odometry toMsg(const cairn::sim::Odometry& o) {
  nav_msgs::msg::Odometry m;
  m.header.stamp = stampOf(o.stamp);
  m.header.frame_id = "odom";
  m.child_frame_id = "base_link";
  m.pose.pose.position.x = o.pose.x;
  m.pose.pose.position.y = o.pose.y;
  m.pose.pose.orientation.z = std::sin(0.5 * o.pose.theta);
  m.pose.pose.orientation.w = std::cos(0.5 * o.pose.theta);
  return m;
}

// A run of the simulator's office without people, the robot driving from its start (2, 12.55) along the corridor.
cairn::sim::SimOutput officeRun(std::uint64_t seed, double to_x, double seconds) {
  namespace sim = cairn::sim;
  const sim::World office = sim::loadWorld(sim::resolveWorldPath("office"));
  sim::SimConfig cfg;
  cfg.seed = seed;
  cfg.people = false;
  cfg.crowd = false;
  sim::Simulator s(office, cfg);
  s.followRoute({{2, 12.55}, {to_x, 12.55}});
  sim::SimOutput out;
  s.advance(seconds, out);
  return out;
}

// base_link -> laser: identity (the simulator's laser sits at the base origin).
tf2_msgs::msg::TFMessage laserMount() {
  tf2_msgs::msg::TFMessage st;
  geometry_msgs::msg::TransformStamped mount;
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "laser";
  mount.transform.rotation.w = 1.0;
  st.transforms.push_back(mount);
  return st;
}

}  // namespace

TEST(SlamComponent, MapsASimulatedRunOverDdsSavesLoadsAndSurvivesBadInput) {
  const cairn::sim::SimOutput out = officeRun(5, 14.0, 25.0);
  ASSERT_GT(out.scans.size(), 100u);

  cairn::testing::InProcessContainer container("slam_container");
  cairn::LoadRequest req{"cairn_graph_slam::SlamNode", "slam"};
  req.parameters["use_verifier"] = false;
  req.parameters["map_publish_period"] = 1.0;
  req.parameters["optimize_every_n_nodes"] = 1;  // an optimization after every node: the map must still wait 1 s
  req.parameters["laser_theta"] = 1.0;  // wrong on purpose: the TF below (identity) must win
  const auto loaded = container.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  container.start();

  // Everything the peer's callbacks write is declared before the peer, so it outlives the peer's spinning thread
  // (the other way round, a /tf or map message arriving at the end wrote into destroyed locals).
  std::mutex mu;
  std::atomic<int> poses{0}, tfs{0};
  geometry_msgs::msg::PoseWithCovarianceStamped last_pose;
  std::vector<double> map_stamps;  // of the maps published while the scans come in
  std::atomic<bool> got_map{false};
  nav_msgs::msg::OccupancyGrid map;
  cairn::testing::PeerNode robot("robot");
  cairn::Node& n = robot.node();
  auto scan_pub = n.create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS::sensor_data().reliable().keep_last(50));
  auto odom_pub = n.create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{}.keep_last(50));
  auto tf_static = n.create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", cairn::QoS::latched());
  auto pose_sub = n.create_subscription<geometry_msgs::msg::PoseWithCovarianceStamped>(
      "slam/pose", cairn::QoS{}, [&](const geometry_msgs::msg::PoseWithCovarianceStamped& m) {
        std::lock_guard l(mu);
        last_pose = m;
        ++poses;
      });
  auto tf_sub = n.create_subscription<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100), [&](const tf2_msgs::msg::TFMessage& m) {
    for (const auto& t : m.transforms)
      if (t.header.frame_id == "map" && t.child_frame_id == "odom") ++tfs;
  });
  auto save = n.create_client<cairn_slam_msgs::srv::SaveState_Request, cairn_slam_msgs::srv::SaveState_Response>("slam/save_state");
  auto load = n.create_client<cairn_slam_msgs::srv::LoadState_Request, cairn_slam_msgs::srv::LoadState_Response>("slam/load_state");
  auto optimize = n.create_client<cairn_slam_msgs::srv::Optimize_Request, cairn_slam_msgs::srv::Optimize_Response>("slam/optimize");
  auto map_counter = n.create_subscription<nav_msgs::msg::OccupancyGrid>(
      "map", cairn::QoS::latched().keep_last(500), [&](const nav_msgs::msg::OccupancyGrid& m) {
        std::lock_guard l(mu);
        map_stamps.push_back(m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec);
      });
  robot.start();
  ASSERT_TRUE(wait_for([&] { return scan_pub->inter_process_subscription_count() > 0 && odom_pub->inter_process_subscription_count() > 0; }, 20s));

  // base_link -> laser: identity; the component must use it, not laser_theta.
  tf_static->publish(laserMount());

  // Paced by the component: the next scan goes out once the pose of the previous one came back (a sensor-data
  // subscription keeps only the newest scans; this test checks every scan is processed, not queueing).
  std::size_t oi = 0;
  int published = 0;
  for (std::size_t i = 0; i < out.scans.size(); ++i) {
    const auto& scan = out.scans[i];
    while (oi < out.odometry.size() && out.odometry[oi].stamp <= scan.stamp + 1e-9) odom_pub->publish(toMsg(out.odometry[oi++]));
    const int before = poses.load();
    scan_pub->publish(toMsg(scan));
    ++published;
    wait_for([&] { return poses.load() > before; }, 500ms);  // one scan in flight at a time
    if (i == out.scans.size() / 2) {
      // Garbage in the middle: a scan with no beams and one with a NaN increment are skipped, not fatal.
      auto bad = toMsg(scan);
      bad.ranges.clear();
      scan_pub->publish(bad);
      bad = toMsg(scan);
      bad.angle_increment = std::numeric_limits<float>::quiet_NaN();
      scan_pub->publish(bad);
    }
  }
  // Every scan gets a pose, but for the first ones (before the base->laser TF arrived) and any the sensor-QoS
  // subscription dropped on a loaded machine.
  EXPECT_GE(poses.load(), published * 9 / 10) << poses.load() << " of " << published;
  EXPECT_GT(tfs.load(), published / 2);
  {
    std::lock_guard l(mu);
    // Rebuilt at most once per map_publish_period (1 s) although every node was followed by an optimization
    // (it used to be rebuilt after each one: ~4 maps per simulated second here).
    EXPECT_GE(map_stamps.size(), 10u);
    for (std::size_t i = 1; i < map_stamps.size(); ++i)
      EXPECT_GE(map_stamps[i] - map_stamps[i - 1], 0.999) << "maps " << i - 1 << " and " << i;
    // The robot drove ~12 m along the corridor from (2, 12.55): the pose (map = first odometry frame) moved too.
    const auto& p = last_pose.pose.pose.position;
    EXPECT_GT(std::hypot(p.x, p.y), 5.0);
  }

  // A late subscriber gets the latched map.
  auto map_sub = n.create_subscription<nav_msgs::msg::OccupancyGrid>("map", cairn::QoS::latched(), [&](const nav_msgs::msg::OccupancyGrid& m) {
    std::lock_guard l(mu);
    map = m;
    got_map = true;
  });
  ASSERT_TRUE(wait_for([&] { return got_map.load(); }, 20s));
  {
    std::lock_guard l(mu);
    EXPECT_EQ(map.header.frame_id, "map");
    EXPECT_NEAR(map.info.resolution, 0.05, 1e-6);
    ASSERT_EQ(map.data.size(), static_cast<std::size_t>(map.info.width) * map.info.height);
    std::size_t occupied = 0, free_cells = 0;
    for (int8_t v : map.data) {
      occupied += v > 65;
      free_cells += v >= 0 && v < 20;
    }
    EXPECT_GT(occupied, 300u);
    EXPECT_GT(free_cells, 3000u);
    // The corridor runs along x (the route): the occupied cells' principal axis is within 10° of it. Scans
    // rotated by the wrong laser_theta (1 rad) would turn the walls by 57°.
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, k = 0;
    for (uint32_t y = 0; y < map.info.height; ++y)
      for (uint32_t x = 0; x < map.info.width; ++x)
        if (map.data[y * map.info.width + x] > 65) {
          sx += x, sy += y, sxx += double(x) * x, syy += double(y) * y, sxy += double(x) * y, ++k;
        }
    const double cxx = sxx / k - (sx / k) * (sx / k), cyy = syy / k - (sy / k) * (sy / k), cxy = sxy / k - (sx / k) * (sy / k);
    const double axis = 0.5 * std::atan2(2 * cxy, cxx - cyy);
    EXPECT_LT(std::abs(axis), 10.0 * M_PI / 180.0) << axis;
  }

  // slam/optimize: a solve that does not make the graph worse, and with republish_map a new map right away
  // (outside map_publish_period).
  std::size_t maps_before = 0;
  {
    std::lock_guard l(mu);
    maps_before = map_stamps.size();
  }
  cairn_slam_msgs::srv::Optimize_Request oq;
  oq.republish_map = true;
  auto orr = optimize->call(oq, 20s);
  ASSERT_TRUE(orr);
  EXPECT_TRUE(orr->success) << orr->message;
  EXPECT_TRUE(std::isfinite(orr->initial_chi2) && std::isfinite(orr->final_chi2));
  EXPECT_LE(orr->final_chi2, orr->initial_chi2 * (1 + 1e-9) + 1e-9) << orr->message;
  EXPECT_FALSE(orr->message.empty());
  EXPECT_TRUE(wait_for([&] {
    std::lock_guard l(mu);
    return map_stamps.size() > maps_before;
  }, 10s)) << "no map after slam/optimize with republish_map";

  const fs::path dir = fs::temp_directory_path() / ("cairn_slam_component_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  cairn_slam_msgs::srv::SaveState_Request sq;
  sq.path = (dir / "state.cslam").string();
  sq.map_stem = (dir / "map").string();
  auto sr = save->call(sq, 20s);
  ASSERT_TRUE(sr);
  EXPECT_TRUE(sr->success) << sr->message;
  EXPECT_GT(sr->nodes, 20u);
  EXPECT_TRUE(fs::exists(dir / "state.cslam"));
  EXPECT_TRUE(fs::exists(dir / "map.pgm"));

  // A truncated state file: a clear error, the node keeps its map and keeps running.
  {
    std::ifstream in(dir / "state.cslam", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(dir / "broken.cslam", std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  }
  cairn_slam_msgs::srv::LoadState_Request lq;
  lq.path = (dir / "broken.cslam").string();
  auto lr = load->call(lq, 20s);
  ASSERT_TRUE(lr);
  EXPECT_FALSE(lr->success);
  EXPECT_NE(lr->message.find("broken.cslam"), std::string::npos) << lr->message;
  lq.path = (dir / "state.cslam").string();
  lq.localization_only = true;
  lr = load->call(lq, 20s);
  ASSERT_TRUE(lr);
  EXPECT_TRUE(lr->success) << lr->message;
  EXPECT_EQ(lr->nodes, sr->nodes);
  // Still alive: a pose for a new scan.
  const int before = poses.load();
  auto again = toMsg(out.scans.back());
  again.header.stamp = stampOf(out.scans.back().stamp + 1.0);
  scan_pub->publish(again);
  EXPECT_TRUE(wait_for([&] { return poses.load() > before; }, 10s));
  fs::remove_all(dir);
}

// map -> odom (REP 105) takes the odometry pose to the map pose: published map->odom composed with the odometry
// at a scan's stamp gives /slam/pose of that scan. The simulator's odometry starts at the robot's start pose (2,
// 12.55) and here, as in the demo, the first scans arrive before the first odometry: the SLAM's local frame then
// starts at the origin, and map->odom taken from it was off by the start pose (12.7 m).
TEST(SlamComponent, MapToOdomTakesTheOdometryToThePoseAlsoWhenTheFirstScansHadNone) {
  const cairn::sim::SimOutput out = officeRun(7, 12.0, 10.0);
  ASSERT_GT(out.scans.size(), 60u);
  ASSERT_GT(std::hypot(out.odometry.front().pose.x, out.odometry.front().pose.y), 10.0);

  cairn::testing::InProcessContainer container("slam_tf_container");
  cairn::LoadRequest req{"cairn_graph_slam::SlamNode", "slam"};
  req.parameters["use_verifier"] = false;
  const auto loaded = container.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  container.start();

  std::mutex mu;
  std::atomic<int> poses{0};
  std::map<double, std::array<double, 3>> slam_pose;  // stamp -> x, y, yaw (map)
  std::map<double, std::array<double, 3>> map_to_odom;
  cairn::testing::PeerNode robot("robot");
  cairn::Node& n = robot.node();
  auto scan_pub = n.create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS::sensor_data().reliable().keep_last(50));
  auto odom_pub = n.create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{}.keep_last(50));
  auto tf_static = n.create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", cairn::QoS::latched());
  auto yaw = [](const geometry_msgs::msg::Quaternion& q) { return 2.0 * std::atan2(q.z, q.w); };
  auto pose_sub = n.create_subscription<geometry_msgs::msg::PoseWithCovarianceStamped>(
      "slam/pose", cairn::QoS{}, [&](const geometry_msgs::msg::PoseWithCovarianceStamped& m) {
        std::lock_guard l(mu);
        slam_pose[cairn::to_seconds(m.header.stamp)] = {m.pose.pose.position.x, m.pose.pose.position.y, yaw(m.pose.pose.orientation)};
        ++poses;
      });
  auto tf_sub = n.create_subscription<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100), [&](const tf2_msgs::msg::TFMessage& m) {
    std::lock_guard l(mu);
    for (const auto& t : m.transforms)
      if (t.header.frame_id == "map" && t.child_frame_id == "odom")
        map_to_odom[cairn::to_seconds(t.header.stamp)] = {t.transform.translation.x, t.transform.translation.y, yaw(t.transform.rotation)};
  });
  robot.start();
  ASSERT_TRUE(wait_for([&] { return scan_pub->inter_process_subscription_count() > 0 && odom_pub->inter_process_subscription_count() > 0; }, 20s));
  tf_static->publish(laserMount());

  std::size_t oi = 0;
  for (std::size_t i = 0; i < out.scans.size(); ++i) {
    const auto& scan = out.scans[i];
    // The first five scans go out before any odometry (the component predicts them); then the odometry up to three
    // scans ahead, so that it has arrived when its scan does: two topics are not delivered in order, and a scan newer
    // than the last odometry continues the last odometry motion (graph_slam::poseAt), exact only where the odometry
    // moves the same in consecutive periods (with one scan of lead, before poseAt extrapolated, a clean-clone CI run
    // once compared odometry one period stale: 5.9 cm).
    const double until = out.scans[std::min(i + 3, out.scans.size() - 1)].stamp;
    while (i >= 5 && oi < out.odometry.size() && out.odometry[oi].stamp <= until + 1e-9) odom_pub->publish(toMsg(out.odometry[oi++]));
    if (i == 5) std::this_thread::sleep_for(100ms);  // the odometry is in before the scan that needs it
    const int before = poses.load();
    scan_pub->publish(toMsg(scan));
    wait_for([&] { return poses.load() > before; }, 500ms);
  }
  ASSERT_TRUE(wait_for([&] {
    std::lock_guard l(mu);
    return map_to_odom.size() >= out.scans.size() * 8 / 10;
  }, 10s));
  robot.stop();
  container.stop();

  // Every scan after the odometry started: map->odom (x) odometry at its stamp == its /slam/pose. A scan that arrives
  // before its odometry continues the last odometry motion: the test's lead makes that rare, but a loaded machine
  // still delays a callback now and then (twice in 28 scans with three busy loops on two cores, before poseAt), and
  // where the robot speeds up or the odometry's noise changes its step the continued motion is not exact, so such
  // scans may be off by up to a period's motion (< 0.1 m here); the rest must be exact.
  std::size_t checked = 0, exact = 0;
  std::lock_guard l(mu);
  for (const auto& [stamp, p] : slam_pose) {
    const auto tf = map_to_odom.find(stamp);
    if (tf == map_to_odom.end() || stamp < out.scans[8].stamp) continue;
    const auto o = std::min_element(out.odometry.begin(), out.odometry.end(),
                                    [&](const auto& a, const auto& b) { return std::abs(a.stamp - stamp) < std::abs(b.stamp - stamp); });
    ASSERT_LT(std::abs(o->stamp - stamp), 1e-6);
    const auto& [tx, ty, th] = tf->second;
    const double x = tx + std::cos(th) * o->pose.x - std::sin(th) * o->pose.y;
    const double y = ty + std::sin(th) * o->pose.x + std::cos(th) * o->pose.y;
    const double dth = std::remainder(th + o->pose.theta - p[2], 2 * M_PI);
    EXPECT_NEAR(x, p[0], 0.1) << "stamp " << stamp;
    EXPECT_NEAR(y, p[1], 0.1) << "stamp " << stamp;
    EXPECT_NEAR(dth, 0.0, 0.05) << "stamp " << stamp;
    exact += std::hypot(x - p[0], y - p[1]) < 1e-3 && std::abs(dth) < 1e-3;
    ++checked;
  }
  EXPECT_GT(checked, out.scans.size() / 2);
  EXPECT_GE(exact * 10, checked * 8) << exact << " of " << checked << " exact";
}
