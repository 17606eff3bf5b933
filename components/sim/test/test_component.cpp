// cairn_sim::Simulator and cairn_sim::LogPlayer in an in-process container, heard from a node in another
// context (everything crosses DDS): scans with the configured beam count and frame, cmd_vel moving the
// odometry, /clock advancing and driving a use_sim_time node, the scripted route and people ground truth,
// CARMEN playback with the log's timestamps, and load / launch-spec validation errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <csignal>
#include <sys/wait.h>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <unistd.h>
#include <vector>

#include "cairn/test_support.hpp"
#include "cairn/container.hpp"
#include "cairn/launch.hpp"
#include "cairn/process.hpp"
#include "log_player.hpp"
#include "cairn/sim/carmen.hpp"
#include "cairn/sim/simulator.hpp"
#include "cairn_sim_msgs/msg/PersonArray.hpp"
#include "cairn_sim_msgs/srv/NavigateTo.hpp"
#include "geometry_msgs/msg/Twist.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "rosgraph_msgs/msg/Clock.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

using namespace std::chrono_literals;

namespace {

const std::string kRoot = CAIRN_SOURCE_ROOT;

constexpr auto waitFor = &cairn::testing::wait_for;  // cairn/test_support.hpp

double seconds(const builtin_interfaces::msg::Time& t) { return t.sec + 1e-9 * t.nanosec; }
int64_t nanos(const builtin_interfaces::msg::Time& t) { return int64_t{t.sec} * 1000000000 + t.nanosec; }
double yawOf(const geometry_msgs::msg::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

// A component in an in-process container spinning on its own thread, and the listening side in its own context
// (every message arrives over DDS).
using Container = cairn::testing::InProcessContainer;
using Listener = cairn::testing::PeerNode;

// What a listener heard. Declared before the Listener whose callbacks write to it, so that it outlives the
// listener's spinning thread (destroyed the other way round, a callback still running pushed into freed
// vectors: test_sim_component segfaulted at the end of its first test in a CI run).
struct Heard {
  std::mutex mu;
  std::vector<sensor_msgs::msg::LaserScan> scans;
  std::vector<nav_msgs::msg::Odometry> odom, truth;
  std::vector<double> clock;
  std::vector<geometry_msgs::msg::TransformStamped> tf;
  std::vector<cairn_sim_msgs::msg::PersonArray> people;
  bool all_dds = true;
};

template <class T>
std::size_t sizeOf(Heard& h, const std::vector<T>& v) {
  std::lock_guard l(h.mu);
  return v.size();
}

}  // namespace

TEST(SimulatorComponent, ScansOdometryClockAndCmdVelOverDds) {
  Container c("sim_container");
  cairn::LoadRequest req{"cairn_sim::Simulator", "simulator"};
  req.parameters["world"] = std::string("office");
  req.parameters["seed"] = int64_t{7};
  req.parameters["real_time_factor"] = 4.0;
  req.parameters["people.crowd"] = false;
  const auto loaded = c.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  c.start();

  Heard h;
  Listener ls("listener");
  auto& n = ls.node();
  auto scan_sub = n.create_subscription<sensor_msgs::msg::LaserScan>(
      "scan", cairn::QoS::sensor_data().keep_last(50), [&](const sensor_msgs::msg::LaserScan& m, const cairn::MessageInfo& info) {
        std::lock_guard l(h.mu);
        h.all_dds = h.all_dds && !info.from_intra_process;
        h.scans.push_back(m);
      });
  auto odom_sub = n.create_subscription<nav_msgs::msg::Odometry>("odom", cairn::QoS{}.keep_last(100), [&](const nav_msgs::msg::Odometry& m) {
    std::lock_guard l(h.mu);
    h.odom.push_back(m);
  });
  auto gt_sub = n.create_subscription<nav_msgs::msg::Odometry>("ground_truth", cairn::QoS{}.keep_last(100), [&](const nav_msgs::msg::Odometry& m) {
    std::lock_guard l(h.mu);
    h.truth.push_back(m);
  });
  auto clock_sub = n.create_subscription<rosgraph_msgs::msg::Clock>("/clock", cairn::QoS{}.keep_last(10), [&](const rosgraph_msgs::msg::Clock& m) {
    std::lock_guard l(h.mu);
    h.clock.push_back(seconds(m.clock));
  });
  auto tf_sub = n.create_subscription<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100), [&](const tf2_msgs::msg::TFMessage& m) {
    std::lock_guard l(h.mu);
    for (const auto& t : m.transforms) h.tf.push_back(t);
  });
  auto cmd_pub = n.create_publisher<geometry_msgs::msg::Twist>("cmd_vel", cairn::QoS{});
  ls.start();

  // ground_truth is its own topic, matched on its own schedule: wait for it too (truth.back() below)
  ASSERT_TRUE(waitFor([&] { return sizeOf(h, h.scans) >= 3 && sizeOf(h, h.odom) >= 20 && sizeOf(h, h.truth) >= 1; }, 30s))
      << "no scans/odometry/ground truth over DDS";
  ASSERT_TRUE(waitFor([&] { return cmd_pub->inter_process_subscription_count() > 0; }, 20s)) << "cmd_vel subscription not discovered";
  {
    std::lock_guard l(h.mu);
    EXPECT_TRUE(h.all_dds);
    const auto& s = h.scans.back();
    EXPECT_EQ(s.header.frame_id, "laser");
    EXPECT_EQ(s.ranges.size(), 720u) << "360 deg at 0.5 deg";
    EXPECT_NEAR(s.angle_increment, M_PI / 360.0, 1e-6);
    std::size_t finite = 0;
    for (float r : s.ranges) finite += std::isfinite(r) && r >= s.range_min && r <= s.range_max;
    EXPECT_GT(finite, 600u) << "the office walls are within 20 m in most directions";
    EXPECT_EQ(h.odom.back().header.frame_id, "odom");
    EXPECT_EQ(h.odom.back().child_frame_id, "base_link");
    EXPECT_EQ(h.truth.back().header.frame_id, "map");
  }
  // Without cmd_vel the robot stands still at the world's start (2, 12.55, 0): odometry noise is ∝ distance.
  nav_msgs::msg::Odometry before;
  {
    std::lock_guard l(h.mu);
    before = h.odom.back();
    EXPECT_NEAR(h.truth.back().pose.pose.position.x, 2.0, 1e-9);
    EXPECT_NEAR(h.truth.back().pose.pose.position.y, 12.55, 1e-9);
  }
  EXPECT_NEAR(before.pose.pose.position.x, 2.0, 1e-9);

  // Drive forward over DDS (repeated within the 0.5 s sim-time command timeout) until odometry shows 1 m.
  geometry_msgs::msg::Twist fwd;
  fwd.linear.x = 0.5;
  const bool moved = waitFor([&] {
    cmd_pub->publish(fwd);
    std::this_thread::sleep_for(15ms);
    std::lock_guard l(h.mu);
    return h.odom.back().pose.pose.position.x > before.pose.pose.position.x + 1.0;
  }, 60s);
  ASSERT_TRUE(moved) << "cmd_vel did not move the odometry";
  {
    nav_msgs::msg::Odometry o;
    {
      std::lock_guard l(h.mu);
      o = h.odom.back();
    }
    EXPECT_GT(o.twist.twist.linear.x, 0.3);
    EXPECT_NEAR(o.pose.pose.position.y, 12.55, 0.1) << "straight along the corridor";
    // Ground truth at the same stamp agrees within the odometry error (1 % scale error + noise). It comes on
    // its own topic, so under load it may arrive after the odometry of the same step: wait for it.
    std::optional<nav_msgs::msg::Odometry> truth;
    const bool compared = waitFor([&] {
      std::lock_guard l(h.mu);
      for (auto it = h.truth.rbegin(); it != h.truth.rend(); ++it)
        if (nanos(it->header.stamp) == nanos(o.header.stamp)) {
          truth = *it;
          return true;
        }
      return false;
    }, 10s);
    ASSERT_TRUE(compared) << "ground_truth and odom share stamps";
    EXPECT_NEAR(truth->pose.pose.position.x - 2.0, (o.pose.pose.position.x - 2.0) / 1.01, 0.05);
  }
  // Turn in place.
  double yaw0;
  {
    std::lock_guard l(h.mu);
    yaw0 = yawOf(h.odom.back().pose.pose.orientation);
  }
  geometry_msgs::msg::Twist turn;
  turn.angular.z = 1.0;
  ASSERT_TRUE(waitFor([&] {
    cmd_pub->publish(turn);
    std::this_thread::sleep_for(15ms);
    std::lock_guard l(h.mu);
    return yawOf(h.odom.back().pose.pose.orientation) > yaw0 + 0.5;
  }, 60s)) << "angular.z did not turn the robot";

  std::lock_guard l(h.mu);
  // /clock: strictly increasing sim time (starting near 0, not wall time), ahead of or equal to the data.
  ASSERT_GE(h.clock.size(), 10u);
  for (std::size_t i = 1; i < h.clock.size(); ++i) EXPECT_GT(h.clock[i], h.clock[i - 1]) << "at " << i;
  EXPECT_GT(h.clock.back(), 2.0);
  EXPECT_LT(h.clock.back(), 1e6) << "sim time, not wall time";
  // /tf odom -> base_link carries exactly the odometry poses.
  std::size_t matched = 0;
  for (const auto& t : h.tf) {
    EXPECT_EQ(t.header.frame_id, "odom");
    EXPECT_EQ(t.child_frame_id, "base_link");
    for (const auto& o : h.odom)
      if (nanos(o.header.stamp) == nanos(t.header.stamp)) {
        EXPECT_DOUBLE_EQ(t.transform.translation.x, o.pose.pose.position.x);
        EXPECT_DOUBLE_EQ(t.transform.rotation.z, o.pose.pose.orientation.z);
        ++matched;
        break;
      }
  }
  EXPECT_GT(matched, 20u);
}

TEST(SimulatorComponent, DrivesItsRoutePublishesPeopleAndDrivesSimTimeNodes) {
  // A small world: a 10 m x 6 m room, a route along its middle and one scripted walker.
  const auto dir = std::filesystem::temp_directory_path() / ("cairn_sim_component_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string world = (dir / "room.yaml").string();
  std::ofstream(world) << "name: room\n"
                          "walls:\n  - [[0, 0], [10, 0], [10, 6], [0, 6], [0, 0]]\n"
                          "robot:\n  start: [1, 3, 0]\n"
                          "routes:\n  line: [[1, 3], [8, 3]]\n"
                          "people:\n  - {kind: scripted, waypoints: [[2, 1], [8, 1]], speed: 1.0, start_time: 0}\n";
  Container c("route_container");
  cairn::LoadRequest req{"cairn_sim::Simulator", "simulator"};
  req.parameters["world"] = world;
  req.parameters["route"] = std::string("line");
  req.parameters["route_loop"] = false;
  req.parameters["real_time_factor"] = 10.0;
  req.parameters["laser.fov_deg"] = 180.0;
  req.parameters["laser.resolution_deg"] = 1.0;
  req.parameters["publish_map_tf"] = true;
  req.parameters["people.rate"] = 250.0;  // above the 100 Hz physics rate: once per physics step
  const auto loaded = c.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  c.start();

  Heard h;
  Listener ls("observer", {{"use_sim_time", true}});
  auto& n = ls.node();
  auto scan_sub = n.create_subscription<sensor_msgs::msg::LaserScan>("scan", cairn::QoS::sensor_data(), [&](const sensor_msgs::msg::LaserScan& m) {
    std::lock_guard l(h.mu);
    h.scans.push_back(m);
  });
  auto gt_sub = n.create_subscription<nav_msgs::msg::Odometry>("ground_truth", cairn::QoS{}.keep_last(100), [&](const nav_msgs::msg::Odometry& m) {
    std::lock_guard l(h.mu);
    h.truth.push_back(m);
  });
  auto people_sub = n.create_subscription<cairn_sim_msgs::msg::PersonArray>("people/ground_truth", cairn::QoS{}.keep_last(100), [&](const cairn_sim_msgs::msg::PersonArray& m) {
    std::lock_guard l(h.mu);
    h.people.push_back(m);
  });
  auto tf_sub = n.create_subscription<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100), [&](const tf2_msgs::msg::TFMessage& m) {
    std::lock_guard l(h.mu);
    for (const auto& t : m.transforms) h.tf.push_back(t);
  });
  ls.start();

  // No cmd_vel at all: the route takes the robot from x = 1 towards x = 8.
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard l(h.mu);
    return !h.truth.empty() && h.truth.back().pose.pose.position.x > 4.0;
  }, 60s)) << "the scripted route did not move the robot";
  ASSERT_TRUE(waitFor([&] { return sizeOf(h, h.people) >= 10 && sizeOf(h, h.scans) >= 3; }, 30s));
  // The observer's clock is the simulator's (use_sim_time over DDS).
  ASSERT_TRUE(waitFor([&] { return n.now().seconds() > 1.0; }, 30s)) << "use_sim_time node did not follow /clock";
  EXPECT_LT(n.now().seconds(), 1e6) << "sim time, not wall time";

  std::lock_guard l(h.mu);
  EXPECT_EQ(h.scans.back().ranges.size(), 181u) << "180 deg at 1 deg";
  EXPECT_EQ(h.scans.back().header.frame_id, "laser");
  EXPECT_NEAR(h.truth.back().pose.pose.position.y, 3.0, 0.2);
  int checked = 0;
  double last_stamp = -1;
  for (const auto& pa : h.people) {
    EXPECT_EQ(pa.header.frame_id, "map");
    EXPECT_GT(seconds(pa.header.stamp), last_stamp + 0.005) << "at most once per 10 ms physics step";
    last_stamp = seconds(pa.header.stamp);
    ASSERT_EQ(pa.people.size(), 1u) << "one scripted walker";
    const auto& p = pa.people[0];
    EXPECT_NEAR(p.position.y, 1.0, 0.05);
    EXPECT_GE(p.position.x, 2.0 - 0.05);
    EXPECT_LE(p.position.x, 8.0 + 0.05);
    EXPECT_NEAR(std::hypot(p.left_leg.x - p.right_leg.x, p.left_leg.y - p.right_leg.y) > 0.0, true, 0);
    if (seconds(pa.header.stamp) > 0.5 && seconds(pa.header.stamp) < 5.5) {  // first leg of the walk: +x at 1 m/s
      EXPECT_NEAR(p.velocity.x, 1.0, 0.05);
      EXPECT_NEAR(p.position.x, 2.0 + seconds(pa.header.stamp), 0.1);
      ++checked;
    }
  }
  EXPECT_GE(checked, 5);

  // publish_map_tf: map -> odom ⊕ odom -> base_link is the ground-truth pose at the same stamp.
  std::map<int64_t, geometry_msgs::msg::TransformStamped> map_odom, odom_base;
  for (const auto& t : h.tf) (t.header.frame_id == "map" ? map_odom : odom_base)[nanos(t.header.stamp)] = t;
  int composed = 0;
  for (const auto& g : h.truth) {
    const auto a = map_odom.find(nanos(g.header.stamp));
    const auto b = odom_base.find(nanos(g.header.stamp));
    if (a == map_odom.end() || b == odom_base.end()) continue;
    EXPECT_EQ(a->second.child_frame_id, "odom");
    const double ya = yawOf(a->second.transform.rotation), yb = yawOf(b->second.transform.rotation);
    const auto& ta = a->second.transform.translation;
    const auto& tb = b->second.transform.translation;
    const double x = ta.x + std::cos(ya) * tb.x - std::sin(ya) * tb.y;
    const double y = ta.y + std::sin(ya) * tb.x + std::cos(ya) * tb.y;
    EXPECT_NEAR(x, g.pose.pose.position.x, 1e-9);
    EXPECT_NEAR(y, g.pose.pose.position.y, 1e-9);
    EXPECT_NEAR(std::remainder(ya + yb - yawOf(g.pose.pose.orientation), 2 * M_PI), 0.0, 1e-9);
    ++composed;
  }
  EXPECT_GT(composed, 20);
  std::filesystem::remove_all(dir);
}

TEST(SimulatorComponent, NavigateToDrivesToAPoseAndANamedLocationAndReportsArrival) {
  // sim/navigate_to: the scripted driving as a goal service (the NavigateTo stand-in of the BT executive).
  const auto dir = std::filesystem::temp_directory_path() / ("cairn_sim_nav_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string world = (dir / "room.yaml").string();
  std::ofstream(world) << "name: room\n"
                          "walls:\n  - [[0, 0], [10, 0], [10, 6], [0, 6], [0, 0]]\n"
                          "regions:\n  - {name: dock, rect: [7, 4, 9, 6]}\n"
                          "robot:\n  start: [1, 3, 0]\n";
  Container c("nav_container");
  cairn::LoadRequest req{"cairn_sim::Simulator", "simulator"};
  req.parameters["world"] = world;
  req.parameters["real_time_factor"] = 20.0;
  req.parameters["laser.resolution_deg"] = 2.0;
  req.parameters["people.world"] = false;
  req.parameters["people.crowd"] = false;
  const auto loaded = c.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  c.start();

  Listener ls("navigator");
  ls.start();
  using cairn_sim_msgs::srv::NavigateTo_Request;
  using cairn_sim_msgs::srv::NavigateTo_Response;
  auto client = ls.node().create_client<NavigateTo_Request, NavigateTo_Response>("/sim/navigate_to");
  ASSERT_TRUE(client->wait_for_service(20s));

  NavigateTo_Request goal;  // a pose
  goal.x = 5.0;
  goal.y = 2.0;
  auto r = client->call(goal, 60s);
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(r->success) << r->message;
  EXPECT_EQ(r->message, "arrived");
  EXPECT_NEAR(std::hypot(r->x - 5.0, r->y - 2.0), 0.0, 0.2);  // RouteConfig::tolerance 0.15 m + braking
  EXPECT_GT(r->elapsed_s, 4.0 / 0.6 * 0.9);  // ~4.1 m at the 0.6 m/s route speed, in sim time

  NavigateTo_Request named;  // a named location: the region's centre
  named.location = "dock";
  r = client->call(named, 60s);
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(r->success) << r->message;
  EXPECT_NEAR(std::hypot(r->x - 8.0, r->y - 5.0), 0.0, 0.2);

  named.location = "moon";  // unknown: an immediate failure naming the known places
  r = client->call(named, 30s);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->success);
  EXPECT_NE(r->message.find("has no region or route 'moon' (known: dock)"), std::string::npos) << r->message;

  NavigateTo_Request far;  // a timeout in sim time: the goal is given up and the robot stops short of it
  far.x = 1.0;
  far.y = 1.0;
  far.timeout_s = 1.0;
  r = client->call(far, 30s);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->success);
  EXPECT_NE(r->message.find("timed out"), std::string::npos) << r->message;
  EXPECT_GT(std::hypot(r->x - 1.0, r->y - 1.0), 1.0);

  // A goal is preempted by a cancel request from another call.
  far.timeout_s = 0.0;
  auto pending = client->async_send(far);
  std::this_thread::sleep_for(50ms);
  NavigateTo_Request cancel;
  cancel.cancel = true;
  r = client->call(cancel, 30s);
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(r->success);
  ASSERT_EQ(pending.wait_for(30s), std::future_status::ready);
  const auto cancelled = pending.get();
  EXPECT_FALSE(cancelled.success);
  EXPECT_EQ(cancelled.message, "cancelled");
}

TEST(SimulatorComponent, ScanStreamOverDdsEqualsTheCoreRunWithTheSameSeed) {
  // The adapter adds nothing to the simulation: in route mode (no cmd_vel) the scans heard over DDS are the
  // core's scans for the same world, seed and route, bit for bit, however the wall timer chunks the steps.
  Container c("det_container");
  cairn::LoadRequest req{"cairn_sim::Simulator", "simulator"};
  req.parameters["world"] = std::string("office");
  req.parameters["route"] = std::string("corridor_patrol");
  req.parameters["seed"] = int64_t{5};
  req.parameters["real_time_factor"] = 5.0;
  cairn::QoSOverride keep;  // every scan from the first one on, whenever the listener is discovered
  keep.reliability = cairn::QoS::Reliability::Reliable;
  keep.durability = cairn::QoS::Durability::TransientLocal;
  keep.depth = 1000;
  req.qos_overrides["/scan"] = keep;
  const auto loaded = c.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  c.start();

  Heard h;
  Listener ls("det_listener");
  auto scan_sub = ls.node().create_subscription<sensor_msgs::msg::LaserScan>(
      "scan", cairn::QoS{}.keep_last(1000).reliable().transient_local(), [&](const sensor_msgs::msg::LaserScan& m) {
        std::lock_guard l(h.mu);
        h.scans.push_back(m);
      });
  ls.start();
  constexpr std::size_t kScans = 30;
  ASSERT_TRUE(waitFor([&] { return sizeOf(h, h.scans) >= kScans; }, 60s));

  cairn::sim::SimConfig cfg;
  cfg.seed = 5;
  auto world = cairn::sim::loadWorld(cairn::sim::resolveWorldPath("office"));
  const auto route = world.routes.at("corridor_patrol");
  cairn::sim::Simulator core(std::move(world), cfg);
  core.followRoute(route, cairn::sim::RouteConfig{.loop = true});
  cairn::sim::SimOutput out;
  core.advance(static_cast<double>(kScans) / cfg.laser.rate, out);
  ASSERT_GE(out.scans.size(), kScans);

  std::lock_guard l(h.mu);
  for (std::size_t i = 0; i < kScans; ++i) {
    const auto& got = h.scans[i];
    const auto& want = out.scans[i];
    EXPECT_NEAR(seconds(got.header.stamp), want.stamp, 1e-9) << "scan " << i;
    ASSERT_EQ(got.ranges.size(), want.ranges.size());
    EXPECT_TRUE(got.ranges == want.ranges) << "scan " << i << " differs from the core's";
    EXPECT_TRUE(got.intensities == want.intensities) << "scan " << i;
  }
}

TEST(LogPlayerComponent, PlaysTheAcesExcerptWithTheLogTimestamps) {
  const std::string file = kRoot + "/test/data/carmen/aces_head60.clf.bz2";
#ifndef CAIRN_SIM_HAVE_BZIP2
  GTEST_SKIP() << "built without bzip2";
#endif
  // Reference: the core's reader.
  std::vector<int64_t> scan_stamps, odom_stamps;
  {
    cairn::sim::CarmenReader r(file);
    cairn::sim::CarmenRecord rec;
    while (r.next(rec)) {
      const double t = cairn::sim::stampOf(rec);
      builtin_interfaces::msg::Time m;
      m.sec = static_cast<int32_t>(std::floor(t));
      m.nanosec = static_cast<uint32_t>(std::round((t - std::floor(t)) * 1e9));
      (std::holds_alternative<cairn::sim::CarmenLaser>(rec) ? scan_stamps : odom_stamps).push_back(nanos(m));
    }
  }
  ASSERT_EQ(scan_stamps.size(), 23u);  // test/data/carmen/PROVENANCE.md
  ASSERT_EQ(odom_stamps.size(), 24u);

  // As fast as possible; reliable transient-local overrides make the count exact whatever the discovery order.
  Container c("log_container");
  cairn::LoadRequest req{"cairn_sim::LogPlayer", "log_player"};
  req.parameters["file"] = file;
  req.parameters["rate"] = 0.0;
  cairn::QoSOverride keep;
  keep.reliability = cairn::QoS::Reliability::Reliable;
  keep.durability = cairn::QoS::Durability::TransientLocal;
  keep.depth = 100;
  req.qos_overrides["/scan"] = keep;
  req.qos_overrides["/odom"] = keep;
  keep.depth = 1;
  req.qos_overrides["/clock"] = keep;
  const auto loaded = c.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  c.start();

  Heard h;
  Listener ls("log_listener");
  auto& n = ls.node();
  const auto q = cairn::QoS{}.keep_last(100).reliable().transient_local();
  auto scan_sub = n.create_subscription<sensor_msgs::msg::LaserScan>("scan", q, [&](const sensor_msgs::msg::LaserScan& m) {
    std::lock_guard l(h.mu);
    h.scans.push_back(m);
  });
  auto odom_sub = n.create_subscription<nav_msgs::msg::Odometry>("odom", q, [&](const nav_msgs::msg::Odometry& m) {
    std::lock_guard l(h.mu);
    h.odom.push_back(m);
  });
  auto clock_sub = n.create_subscription<rosgraph_msgs::msg::Clock>("/clock", cairn::QoS{}.keep_last(1).reliable().transient_local(),
                                                                   [&](const rosgraph_msgs::msg::Clock& m) {
                                                                     std::lock_guard l(h.mu);
                                                                     h.clock.push_back(seconds(m.clock));
                                                                   });
  ls.start();
  const double last = std::max(scan_stamps.back(), odom_stamps.back()) * 1e-9;
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard l(h.mu);
    return h.scans.size() >= 23 && h.odom.size() >= 24 && !h.clock.empty() && std::abs(h.clock.back() - last) < 1e-6;
  }, 30s)) << "log not played completely";
  std::this_thread::sleep_for(200ms);  // nothing more may arrive

  std::lock_guard l(h.mu);
  ASSERT_EQ(h.scans.size(), 23u);
  ASSERT_EQ(h.odom.size(), 24u);
  for (std::size_t i = 0; i < h.scans.size(); ++i) {
    EXPECT_EQ(nanos(h.scans[i].header.stamp), scan_stamps[i]) << "scan " << i;
    EXPECT_EQ(h.scans[i].header.frame_id, "laser");
    EXPECT_EQ(h.scans[i].ranges.size(), 180u);
  }
  for (std::size_t i = 0; i < h.odom.size(); ++i) EXPECT_EQ(nanos(h.odom[i].header.stamp), odom_stamps[i]) << "odom " << i;
  EXPECT_EQ(h.odom[0].header.frame_id, "odom");
}

namespace {
// Reference stamps (ns) of a log's laser and odometry records, in file order.
void referenceStamps(const std::string& file, std::vector<int64_t>& scans, std::vector<int64_t>& odoms, std::size_t limit = 0) {
  cairn::sim::CarmenReader r(file);
  cairn::sim::CarmenRecord rec;
  for (std::size_t n = 0; (limit == 0 || n < limit) && r.next(rec); ++n) {
    const double t = cairn::sim::stampOf(rec);
    builtin_interfaces::msg::Time m;
    m.sec = static_cast<int32_t>(std::floor(t));
    m.nanosec = static_cast<uint32_t>(std::round((t - std::floor(t)) * 1e9));
    (std::holds_alternative<cairn::sim::CarmenLaser>(rec) ? scans : odoms).push_back(nanos(m));
  }
}

// A reliable keep-all listener on scan, odom and /clock (everything acknowledged is kept).
struct LogListener {
  Listener ls{"log_listener_" + std::to_string(::getpid())};
  std::mutex mu;
  std::vector<int64_t> scans, odoms;
  std::vector<double> clock;
  std::shared_ptr<cairn::Subscription<sensor_msgs::msg::LaserScan>> scan_sub;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::Odometry>> odom_sub;
  std::shared_ptr<cairn::Subscription<rosgraph_msgs::msg::Clock>> clock_sub;
  // Members are destroyed after the destructor's body: stop the spinning thread first.
  ~LogListener() { ls.stop(); }
  LogListener() {
    const auto q = cairn::QoS{}.keep_all().reliable();
    auto& n = ls.node();
    scan_sub = n.create_subscription<sensor_msgs::msg::LaserScan>("scan", q, [this](const sensor_msgs::msg::LaserScan& m) {
      std::lock_guard l(mu);
      scans.push_back(nanos(m.header.stamp));
    });
    odom_sub = n.create_subscription<nav_msgs::msg::Odometry>("odom", q, [this](const nav_msgs::msg::Odometry& m) {
      std::lock_guard l(mu);
      odoms.push_back(nanos(m.header.stamp));
    });
    clock_sub = n.create_subscription<rosgraph_msgs::msg::Clock>("/clock", q, [this](const rosgraph_msgs::msg::Clock& m) {
      std::lock_guard l(mu);
      clock.push_back(seconds(m.clock));
    });
    ls.start();
  }
};
}  // namespace

TEST(LogPlayerComponent, FullAcesLogPacedByItsConsumerWithBoundedMemory) {
  // The whole ACES log (14749 records) over DDS, each record published only after the listener acknowledged the
  // previous one: every message arrives, with the reader's stamps, while the player holds at most `lookahead`.
  const std::string file = kRoot + "/../shared/data/slam_logs_carmen/radish/aces.clf.bz2";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
#ifndef CAIRN_SIM_HAVE_BZIP2
  GTEST_SKIP() << "built without bzip2";
#endif
  std::vector<int64_t> scan_stamps, odom_stamps;
  referenceStamps(file, scan_stamps, odom_stamps);
  ASSERT_EQ(scan_stamps.size(), 7374u);
  ASSERT_EQ(odom_stamps.size(), 7375u);

  LogListener h;
  Container c("aces_container");
  cairn::LoadRequest req{"cairn_sim::LogPlayer", "log_player"};
  req.parameters["file"] = file;
  req.parameters["rate"] = 0.0;
  req.parameters["pace"] = std::string("consumers");
  req.parameters["lookahead"] = int64_t{16};
  req.parameters["wait_for_subscribers"] = int64_t{1};
  const auto loaded = c.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  c.start();
  const auto player = std::static_pointer_cast<cairn_sim::LogPlayer>(c.manager().get(loaded.unique_id));
  ASSERT_TRUE(waitFor([&] { return player->finished(); }, 100s)) << "played " << player->scansPublished();
  EXPECT_FALSE(player->failed());
  EXPECT_EQ(player->scansPublished(), 7374u);
  EXPECT_EQ(player->odometryPublished(), 7375u);
  EXPECT_LE(player->maxBufferedRecords(), 16u) << "memory grows with the log";
  EXPECT_GE(player->maxBufferedRecords(), 1u);
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard l(h.mu);
    return h.scans.size() >= 7374 && h.odoms.size() >= 7375;
  }, 30s));
  std::lock_guard l(h.mu);
  EXPECT_TRUE(h.scans == scan_stamps) << "scan stamps differ from the log";
  EXPECT_TRUE(h.odoms == odom_stamps) << "odometry stamps differ from the log";
  ASSERT_FALSE(h.clock.empty());
  EXPECT_NEAR(h.clock.back(), std::max(scan_stamps.back(), odom_stamps.back()) * 1e-9, 1e-6);
  EXPECT_TRUE(std::is_sorted(h.clock.begin(), h.clock.end()));
}

TEST(LogPlayCli, PublishesARecordLimitOverDdsAndExits) {
  // `cairn log play` as a subprocess (it loads the LogPlayer component in-process): 300 records of the excerpt
  // log, started once this test's subscription is matched, paced by its acknowledgments (20 records per
  // acknowledgment round: across processes an acknowledgment takes one Cyclone heartbeat period, 100 ms).
  std::string file = kRoot + "/../shared/data/slam_logs_carmen/radish/aces.clf.bz2";
  std::size_t limit = 300;
  if (!std::filesystem::exists(file)) file = kRoot + "/test/data/carmen/aces_corrected_head162.log.gz", limit = 120;
  std::vector<int64_t> scan_stamps, odom_stamps;
  referenceStamps(file, scan_stamps, odom_stamps, limit);
  ASSERT_EQ(scan_stamps.size() + odom_stamps.size(), limit);
  LogListener h;
  const pid_t pid = cairn::spawn_process({CAIRN_LOG_EXE, "play", file, "--limit", std::to_string(limit), "--pace",
                                          "consumers", "--wait-subscribers", "1", "-p", "ack_window:=20"});
  int status = 0;
  ASSERT_TRUE(waitFor([&] { return ::waitpid(pid, &status, WNOHANG) == pid; }, 60s)) << "cairn log play did not exit";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cairn::describe_wait_status(status);
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard l(h.mu);
    return h.scans.size() + h.odoms.size() >= limit;
  }, 10s));
  std::this_thread::sleep_for(100ms);
  std::lock_guard l(h.mu);
  EXPECT_TRUE(h.scans == scan_stamps);
  EXPECT_TRUE(h.odoms == odom_stamps);
}

// `cairn-log <args>` with stderr folded into the output; the exit code (-1 if it did not exit normally).
static std::pair<int, std::string> runCairnLog(const std::string& args) {
  FILE* f = ::popen((std::string(CAIRN_LOG_EXE) + " " + args + " 2>&1").c_str(), "r");
  if (f == nullptr) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, f) != nullptr) out += buf;
  const int status = ::pclose(f);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(LogPlayCli, ABadLogIsOneErrorLineNamingFileAndLineAndExitCode2) {
  const auto [code, out] = runCairnLog("play " + kRoot + "/components/sim/test/data/bad_log.clf");
  EXPECT_EQ(code, 2) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_NE(out.find("bad_log.clf:3:"), std::string::npos) << out;
}

TEST(LogPlayCli, AnUnknownParameterIsOneErrorLineAndNothingPlays) {
  // -p with a name LogPlayer does not declare used to be ignored (exit 0, the log played)
  const auto [code, out] = runCairnLog("play " + kRoot + "/test/data/carmen/aces_head60.clf --limit 3 -p foo:=1");
  EXPECT_EQ(code, 2) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  // the container's load refuses it (as launch validation does), before the log is opened
  EXPECT_EQ(out.rfind("cairn: params.foo: cairn_sim::LogPlayer (/log_player) has no such parameter (declared: ", 0), 0u)
      << out;
}

TEST(LogPlayerComponent, BadLogsAreLoadErrorsNamingFileAndLine) {
  cairn::ComponentLoader loader;
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentManager mgr(ctx, exec, "bad_log_container", loader);
  cairn::LoadRequest req{"cairn_sim::LogPlayer", "log_player"};
  req.parameters["file"] = std::string("/nonexistent/run.clf");
  auto r = mgr.load(req);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("/nonexistent/run.clf"), std::string::npos) << r.error;

  const std::string bad = kRoot + "/components/sim/test/data/bad_log.clf";
  req.parameters["file"] = bad;
  r = mgr.load(req);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("bad_log.clf:3: FLASER: expected 3 range readings"), std::string::npos) << r.error;

  req.parameters["skip_malformed"] = true;
  r = mgr.load(req);
  EXPECT_TRUE(r.ok) << r.error;

  cairn::LoadRequest none{"cairn_sim::LogPlayer", "no_file"};
  r = mgr.load(none);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("parameter 'file' is required"), std::string::npos) << r.error;
}

namespace {
std::string launchError(const std::string& cls, const std::string& params) {
  return cairn::launch_spec_error(
        "containers:\n  - name: c\n    components:\n      - class: " + cls + "\n        params: " + params + "\n",
      "sim.yaml");
}
}  // namespace

TEST(SimulatorComponent, LaunchSpecValidationNamesFileLineAndParameter) {
  EXPECT_EQ(launchError("cairn_sim::Simulator", "{world: warehouse, route: room_tour, seed: 3, real_time_factor: 20, "
                                               "laser.fov_deg: 180, laser.resolution_deg: 0.25, odometry.scale_error: 0.02}"),
            "");
  // Constructor errors name the component's line, parameter type/range errors the params line.
  auto e = launchError("cairn_sim::Simulator", "{world: atlantis}");
  EXPECT_EQ(e.rfind("sim.yaml:4: cairn_sim::Simulator (/simulator) cannot be constructed: ", 0), 0u) << e;
  EXPECT_NE(e.find("world: 'atlantis'"), std::string::npos) << e;
  e = launchError("cairn_sim::Simulator", "{world: office, route: to_the_moon}");
  EXPECT_EQ(e.rfind("sim.yaml:4: ", 0), 0u) << e;
  EXPECT_NE(e.find("no route 'to_the_moon' (routes: corridor_patrol, visit_kitchen)"), std::string::npos) << e;
  e = launchError("cairn_sim::Simulator", "{laser.fov_deg: 400}");
  EXPECT_EQ(e.rfind("sim.yaml:5: ", 0), 0u) << e;
  EXPECT_NE(e.find("laser.fov_deg"), std::string::npos) << e;
  e = launchError("cairn_sim::Simulator", "{real_time_factor: fast}");
  EXPECT_NE(e.find("'real_time_factor' expects double"), std::string::npos) << e;
  e = launchError("cairn_sim::Simulator", "{people.file: /nonexistent/walkers.csv}");
  EXPECT_NE(e.find("/nonexistent/walkers.csv"), std::string::npos) << e;
  // above the physics rate the core gave the step rate instead (200 Hz at physics_dt 0.01 s: 100 scans a second)
  e = launchError("cairn_sim::Simulator", "{laser.rate: 200}");
  EXPECT_NE(e.find("laser.rate: 200 Hz is more than one message per physics step (physics_dt 0.01 s: at most 100 Hz)"),
            std::string::npos) << e;
  e = launchError("cairn_sim::Simulator", "{odom_rate: 500, physics_dt: 0.005}");
  EXPECT_NE(e.find("odom_rate: 500 Hz is more than one message per physics step (physics_dt 0.005 s: at most 200 Hz)"),
            std::string::npos) << e;
  EXPECT_EQ(launchError("cairn_sim::Simulator", "{laser.rate: 200, physics_dt: 0.005}"), "");
  e = launchError("cairn_sim::Simulator", "{laser_rate: 10}");
  EXPECT_NE(e.find("laser_rate"), std::string::npos) << e;
  e = launchError("cairn_sim::LogPlayer", "{file: " + kRoot + "/components/sim/test/data/bad_log.clf}");
  EXPECT_EQ(e.rfind("sim.yaml:4: ", 0), 0u) << e;
  EXPECT_NE(e.find("bad_log.clf:3: FLASER"), std::string::npos) << e;
  EXPECT_EQ(launchError("cairn_sim::LogPlayer", "{file: " + kRoot + "/test/data/carmen/aces_head60.clf, rate: 2.0}"), "");
  e = launchError("cairn_sim::LogPlayer", "{file: " + kRoot + "/test/data/carmen/aces_head60.clf, rate: 1.0e-300}");
  EXPECT_NE(e.find("rate: 1e-300 (expected 0 = no pacing, or 0.001 to 1000)"), std::string::npos) << e;
}

TEST(SimulatorComponent, TheShippedDemoLaunchSpecValidates) {
  // Paths in the spec (urdf_file) are relative to the repository root, where `cairn launch` is run.
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(kRoot);
  cairn::ComponentLoader loader;
  std::string error;
  try {
    cairn::validate_launch_spec(cairn::parse_launch_spec("launch_specs/sim_demo.yaml"), loader);
  } catch (const cairn::LaunchError& e) {
    error = e.what();
  }
  std::filesystem::current_path(cwd);
  EXPECT_EQ(error, "");
}
