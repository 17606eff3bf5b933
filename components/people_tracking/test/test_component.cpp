// cairn_people_tracking::PeopleTracker in a container: synthetic scans of two walking people (the core's scene
// generator, seeded) and odometry of a moving robot arrive over DDS from another context; tracks must come back
// on people/tracks with stable ids at the people's positions in the odometry frame (robot motion compensated),
// the follow service must select the guide, scan_filtered must hide only the guide (mask.people: guide, Yuan
// §3.2.1), and malformed scans must be skipped without stopping the component. Also: launch-spec validation of
// the component's parameters.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include "cairn/test_support.hpp"
#include "cairn/parameter_msgs.hpp"
#include "cairn/container.hpp"
#include "cairn/launch.hpp"
#include "cairn/people_tracking/scene.hpp"
#include "cairn_people_msgs/msg/GuideState.hpp"
#include "cairn_people_msgs/msg/PersonDetections.hpp"
#include "cairn_people_msgs/msg/TrackedPersons.hpp"
#include "cairn_people_msgs/srv/Follow.hpp"
#include "nav_msgs/msg/OccupancyGrid.hpp"
#include "rcl_interfaces/srv/SetParameters.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

using namespace std::chrono_literals;
namespace pt = cairn::people_tracking;
namespace pmsg = cairn_people_msgs::msg;
namespace psrv = cairn_people_msgs::srv;

namespace {

builtin_interfaces::msg::Time stampOf(double s) {
  builtin_interfaces::msg::Time t;
  t.sec = static_cast<int32_t>(std::floor(s));
  t.nanosec = static_cast<uint32_t>(std::llround((s - std::floor(s)) * 1e9));
  return t;
}

sensor_msgs::msg::LaserScan toMsg(const pt::LaserScan& s) {
  sensor_msgs::msg::LaserScan m;
  m.header.stamp = stampOf(s.stamp);
  m.header.frame_id = "laser";
  m.angle_min = static_cast<float>(s.angle_min);
  m.angle_increment = static_cast<float>(s.angle_increment);
  m.angle_max = static_cast<float>(s.angle_min + s.angle_increment * static_cast<double>(s.ranges.size() - 1));
  m.range_min = static_cast<float>(s.range_min);
  m.range_max = static_cast<float>(s.range_max);
  m.ranges = s.ranges;
  return m;
}

// Everything the test's own node hears, guarded by one mutex.
struct Heard {
  std::mutex mu;
  std::map<int64_t, pmsg::TrackedPersons> tracks;  // by scan stamp (ns)
  std::map<int64_t, pmsg::GuideState> guide;
  std::map<int64_t, sensor_msgs::msg::LaserScan> masked;
};
int64_t key(const builtin_interfaces::msg::Time& t) { return int64_t{t.sec} * 1000000000 + t.nanosec; }
// The message heard for the scan stamped `t` (seconds), or nullptr if none was.
template <class M>
const M* heardAt(const std::map<int64_t, M>& heard, double t) {
  const auto it = heard.find(key(stampOf(t)));
  return it == heard.end() ? nullptr : &it->second;
}

constexpr auto waitFor = &cairn::testing::wait_for;  // cairn/test_support.hpp

using Spinner = cairn::testing::Spinner;  // cairn/test_support.hpp

// Two walkers and a robot driving forward while turning slowly; world frame == odometry frame.
struct World {
  pt::WalkerState a, b;
  Eigen::Vector2d va{0.6, 0.0}, vb{0.4, 0.05};
  double robot_v = 0.3, robot_w = 0.05;  // m/s, rad/s
  pt::LaserModel laser;
  std::mt19937_64 rng{6};  // seed: issue 6
  // Laser in base_link: ahead, to the left and turned by 0.3 rad, so a component ignoring the mount misplaces
  // people at 3 m by ~1 m.
  pt::Pose2 mount{0.30, 0.10, 0.30};
  std::vector<Eigen::Vector2d> static_legs;  // leg-like static objects (none unless a test adds them)

  World() {
    a.position = {2.5, 1.2};
    b.position = {4.5, -1.3};
    a.heading = 0.0;
    b.heading = std::atan2(vb.y(), vb.x());
    a.gait_phase = 0.3;
    b.gait_phase = 2.0;
  }
  pt::Pose2 robot(double t) const {
    // exact arc of constant (v, w) from the origin
    const double th = robot_w * t;
    return pt::Pose2{robot_v / robot_w * std::sin(th), robot_v / robot_w * (1 - std::cos(th)), th};
  }
  pt::Pose2 laserPose(double t) const {
    return robot(t) * mount;
  }
  tf2_msgs::msg::TFMessage mountTf() const {
    geometry_msgs::msg::TransformStamped m;
    m.header.frame_id = "base_link";
    m.child_frame_id = "laser";
    m.transform.translation.x = mount.x;
    m.transform.translation.y = mount.y;
    m.transform.rotation.z = std::sin(mount.theta / 2);
    m.transform.rotation.w = std::cos(mount.theta / 2);
    tf2_msgs::msg::TFMessage tf;
    tf.transforms.push_back(m);
    return tf;
  }
  double hide_a_from = -1, hide_a_to = -1;  // scan time [s] during which A's legs are not seen (a box instead)
  Eigen::Vector2d personA(double t) const { return Eigen::Vector2d(2.5, 1.2) + va * t; }
  Eigen::Vector2d personB(double t) const { return Eigen::Vector2d(4.5, -1.3) + vb * t; }

  pt::LaserScan scanAt(double t, double dt) {
    a.position = personA(t);
    b.position = personB(t);
    if (t > 0) {
      pt::advanceGait(a, va.norm() * dt, dt);
      pt::advanceGait(b, vb.norm() * dt, dt);
    }
    pt::Scene scene;
    scene.addSegment({10.0, -6.0}, {10.0, 6.0}, pt::ObjectClass::kWall);
    scene.addSegment({-2.0, -4.0}, {10.0, -4.0}, pt::ObjectClass::kWall);
    scene.addSegment({-2.0, 4.5}, {10.0, 4.5}, pt::ObjectClass::kWall);
    scene.addBox({7.0, 2.5}, 0.4, 0.3, 0.2, pt::ObjectClass::kClutter);
    for (const Eigen::Vector2d& c : static_legs) scene.addCircle(c, 0.06, pt::ObjectClass::kTableLeg);
    if (t >= hide_a_from && t < hide_a_to) {
      scene.addBox(a.position, 0.12, 0.12, 0.0, pt::ObjectClass::kClutter);  // returns where A is, but no legs
    } else {
      pt::addWalker(scene, a, 0);
    }
    pt::addWalker(scene, b, 1);
    return pt::renderScan(scene, laserPose(t), laser, t, rng).scan;
  }
  nav_msgs::msg::Odometry odomAt(double t) const {
    nav_msgs::msg::Odometry o;
    o.header.stamp = stampOf(t);
    o.header.frame_id = "odom";
    o.child_frame_id = "base_link";
    const auto p = robot(t);
    o.pose.pose.position.x = p.x;
    o.pose.pose.position.y = p.y;
    o.pose.pose.orientation.z = std::sin(p.theta / 2);
    o.pose.pose.orientation.w = std::cos(p.theta / 2);
    o.twist.twist.linear.x = robot_v;
    o.twist.twist.angular.z = robot_w;
    return o;
  }
};

// Id of the only track within `radius` of p, or nullopt.
std::optional<uint32_t> trackNear(const pmsg::TrackedPersons& m, const Eigen::Vector2d& p, double radius) {
  std::optional<uint32_t> id;
  for (const auto& t : m.tracks)
    if (std::hypot(t.position.x - p.x(), t.position.y - p.y()) < radius) {
      if (id) return std::nullopt;
      id = t.track_id;
    }
  return id;
}

// The component in its own Context with the laser mount from parameters (nobody publishes TF for `base_frame`,
// so after `tf_timeout` of scan time it falls back to sensor_x/y/yaw), and a "sim" node in another Context
// (so over DDS) publishing scans and odometry and hearing people/tracks.
struct FallbackMountRig {
  cairn::ComponentLoader loader;
  std::shared_ptr<cairn::Context> ctx = cairn::Context::create(), sim_ctx = cairn::Context::create();
  cairn::Executor exec, sim_exec;
  std::unique_ptr<cairn::ComponentManager> mgr;
  std::unique_ptr<Spinner> spinner, sim_spinner;
  std::unique_ptr<cairn::Node> sim;
  Heard heard;
  std::shared_ptr<cairn::Publisher<sensor_msgs::msg::LaserScan>> scan_pub;
  std::shared_ptr<cairn::Publisher<nav_msgs::msg::Odometry>> odom_pub;
  std::shared_ptr<cairn::Subscription<pmsg::TrackedPersons>> tracks_sub;
  std::map<int64_t, sensor_msgs::msg::LaserScan> sent;  // by stamp, under heard.mu
  double tf_timeout;

  // Loads the component (ASSERTs inside: call through ASSERT_NO_FATAL_FAILURE(rig.start(...))).
  void start(const std::string& container, const World& world, double tf_timeout_s,
             const std::map<std::string, cairn::ParameterValue>& extra = {}) {
    tf_timeout = tf_timeout_s;
    mgr = std::make_unique<cairn::ComponentManager>(ctx, exec, container, loader);
    cairn::LoadRequest req{"cairn_people_tracking::PeopleTracker", "people_tracker"};
    req.parameters["tf_timeout"] = tf_timeout_s;
    req.parameters["base_frame"] = std::string("base_footprint");  // nobody publishes it, whatever is on /tf_static
    req.parameters["sensor_x"] = world.mount.x;
    req.parameters["sensor_y"] = world.mount.y;
    req.parameters["sensor_yaw"] = world.mount.theta;
    for (const auto& [k, v] : extra) req.parameters[k] = v;
    const auto loaded = mgr->load(req);
    ASSERT_TRUE(loaded.ok) << loaded.error;
    spinner = std::make_unique<Spinner>(exec);
    cairn::NodeOptions o("sim", &sim_exec);
    o.context = sim_ctx;
    o.start_parameter_services = false;
    sim = std::make_unique<cairn::Node>(o);
    scan_pub = sim->create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS{});
    odom_pub = sim->create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{});
    tracks_sub = sim->create_subscription<pmsg::TrackedPersons>("people/tracks", cairn::QoS{}, [this](const pmsg::TrackedPersons& m) {
      std::lock_guard l(heard.mu);
      heard.tracks[key(m.header.stamp)] = m;
    });
    sim_spinner = std::make_unique<Spinner>(sim_exec);
    ASSERT_TRUE(waitFor([&] { return scan_pub->inter_process_subscription_count() > 0 && odom_pub->inter_process_subscription_count() > 0; }, 20s));
    ASSERT_TRUE(waitFor([&] { return tracks_sub->publisher_count_inter_process() > 0; }, 20s));
  }
  // Scans and odometry of `world` at t0 + k dt (k < steps), each after the reply to the previous one (reliable
  // and in order); scans within the TF timeout get no reply, so their wait is short.
  // answered_through(k): the newest scan whose tracks are expected once scan k is sent (default k; fewer when
  // scans wait for a lagging input). The next scan is sent after that reply, or after one scan period when no new
  // reply is due: the scan topic is best effort, and a burst of scans can lose some.
  void play(World& world, double t0, int steps, double dt, const std::function<void(int k, double t)>& before_scan = {},
            const std::function<int(int k)>& answered_through = {}) {
    for (int k = 0; k < steps; ++k) {
      const double t = t0 + k * dt;
      if (before_scan) before_scan(k, t);
      pt::LaserScan s = world.scanAt(k * dt, dt);
      s.stamp = t;
      auto odom = world.odomAt(k * dt);
      odom.header.stamp = stampOf(t);
      odom_pub->publish(odom);
      // The odometry in the component's reader before the scan is sent: the two topics are delivered
      // independently, and under CPU starvation a scan could otherwise wait for its odometry (odom_queue) past
      // the reply timeout below.
      odom_pub->wait_for_all_acked(5s);
      const sensor_msgs::msg::LaserScan msg = toMsg(s);
      {
        std::lock_guard l(heard.mu);
        sent[key(msg.header.stamp)] = msg;
      }
      scan_pub->publish(msg);
      const int j = answered_through ? answered_through(k) : k;
      if (j < 0) continue;
      if (answered_through && k > 0 && j == answered_through(k - 1)) {
        std::this_thread::sleep_for(std::chrono::duration<double>(dt));
        continue;
      }
      waitFor([&] {
        std::lock_guard l(heard.mu);
        return heardAt(heard.tracks, t0 + j * dt) != nullptr;
      }, j * dt < tf_timeout + 0.1 ? 200ms : 5s);
    }
  }
  // Stops both executors: afterwards `heard` no longer changes.
  void stop() {
    if (sim_spinner) sim_spinner->stop();
    if (spinner) spinner->stop();
  }
  ~FallbackMountRig() { stop(); }
};

}  // namespace

TEST(PeopleTrackerComponent, TracksWalkingPeopleOverDdsWithStableIdsFollowsAndMasksTheGuide) {
  // The component, in an in-process container.
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "people_container", loader);
  cairn::LoadRequest req{"cairn_people_tracking::PeopleTracker", "people_tracker"};
  req.parameters["guide.select_max_distance"] = 5.0;
  req.parameters["mask.people"] = std::string("guide");
  req.parameters["mask.mode"] = std::string("tangents");  // Yuan's rule: the beam towards the centre is masked too
  const auto loaded = mgr.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  Spinner spinner(exec);

  // The "robot" publishing scans and odometry from another context: everything goes over DDS.
  auto sim_ctx = cairn::Context::create();
  cairn::Executor sim_exec;
  cairn::NodeOptions o("sim", &sim_exec);
  o.context = sim_ctx;
  o.start_parameter_services = false;
  cairn::Node sim(o);
  Heard heard;
  auto scan_pub = sim.create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS::sensor_data());
  auto odom_pub = sim.create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{});
  // The laser mount comes from TF only (the component's sensor_x/y/yaw stay 0).
  auto tf_static_pub = sim.create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", cairn::QoS::latched());
  auto tracks_sub = sim.create_subscription<pmsg::TrackedPersons>("people/tracks", cairn::QoS{}, [&](const pmsg::TrackedPersons& m, const cairn::MessageInfo& info) {
    EXPECT_FALSE(info.from_intra_process);
    std::lock_guard l(heard.mu);
    heard.tracks[key(m.header.stamp)] = m;
  });
  auto guide_sub = sim.create_subscription<pmsg::GuideState>("people/guide", cairn::QoS{}, [&](const pmsg::GuideState& m) {
    std::lock_guard l(heard.mu);
    heard.guide[key(m.header.stamp)] = m;
  });
  auto masked_sub = sim.create_subscription<sensor_msgs::msg::LaserScan>("scan_filtered", cairn::QoS::sensor_data(), [&](const sensor_msgs::msg::LaserScan& m) {
    std::lock_guard l(heard.mu);
    heard.masked[key(m.header.stamp)] = m;
  });
  auto follow = sim.create_client<psrv::Follow_Request, psrv::Follow_Response>("people/follow");
  Spinner sim_spinner(sim_exec);
  ASSERT_TRUE(waitFor([&] { return scan_pub->inter_process_subscription_count() > 0 && odom_pub->inter_process_subscription_count() > 0; }, 20s))
      << "the component's subscriptions were not discovered";
  World world;
  tf_static_pub->publish(world.mountTf());
  ASSERT_TRUE(waitFor([&] { return tf_static_pub->inter_process_subscription_count() > 0; }, 20s));

  auto received = [&](double t) {
    std::lock_guard l(heard.mu);
    return heardAt(heard.tracks, t) != nullptr;
  };

  const double dt = 1.0 / 15.0;
  const int steps = 75;
  const int select_at = 30;
  std::map<int, sensor_msgs::msg::LaserScan> sent;
  std::optional<uint32_t> guide_reply;
  int lost = 0;
  for (int k = 0; k < steps; ++k) {
    const double t = 100.0 + k * dt;  // stamps in seconds; odometry and scans share them
    const double tl = k * dt;
    pt::LaserScan s = world.scanAt(tl, dt);
    s.stamp = t;
    auto odom = world.odomAt(tl);
    odom.header.stamp = stampOf(t);
    odom_pub->publish(odom);
    sent[k] = toMsg(s);
    scan_pub->publish(sent[k]);
    // Lock step: one scan in flight. A scan lost on the best-effort topic just counts as lost.
    if (!waitFor([&] { return received(t); }, 3s)) ++lost;

    if (k == select_at) {
      psrv::Follow_Request rq;
      rq.command = psrv::Follow_Request_Constants::CLOSEST_IN_FRONT;
      const auto rs = follow->call(rq, 20s);
      ASSERT_TRUE(rs.has_value()) << "follow service did not answer";
      ASSERT_TRUE(rs->success) << rs->message;
      guide_reply = static_cast<uint32_t>(rs->track_id);
    }
  }
  EXPECT_LE(lost, 5) << "scans without a tracks message";
  sim_spinner.stop();  // no more callbacks: `heard` is ours
  spinner.stop();

  std::lock_guard l(heard.mu);
  // After a warm-up of 15 scans: each person is matched by exactly one track within 0.35 m in most scans, the
  // matched id never changes, and the two people never share an id. Positions are compared in the odometry
  // frame, so a missing robot-motion compensation (the robot moves ~1.1 m and turns ~14 deg) fails this.
  std::optional<uint32_t> id_a, id_b;
  int matched_a = 0, matched_b = 0, considered = 0;
  for (int k = 15; k < steps; ++k) {
    const double t = 100.0 + k * dt;
    const auto* msg = heardAt(heard.tracks, t);
    if (!msg) continue;
    ++considered;
    EXPECT_EQ(msg->header.frame_id, "odom");
    const auto a = trackNear(*msg, world.personA(k * dt), 0.35);
    const auto b = trackNear(*msg, world.personB(k * dt), 0.35);
    if (a) {
      ++matched_a;
      if (!id_a) id_a = a;
      EXPECT_EQ(*a, *id_a) << "person A changed id at scan " << k;
    }
    if (b) {
      ++matched_b;
      if (!id_b) id_b = b;
      EXPECT_EQ(*b, *id_b) << "person B changed id at scan " << k;
    }
    for (const auto& tr : msg->tracks) {
      EXPECT_LT(std::hypot(tr.velocity.x, tr.velocity.y), 2.0)
          << "implausible speed of track " << tr.track_id << " at (" << tr.position.x << ", " << tr.position.y
          << "), scan " << k;
    }
  }
  ASSERT_GE(considered, steps - 15 - 5);
  EXPECT_GE(matched_a, considered * 9 / 10);
  EXPECT_GE(matched_b, considered * 9 / 10);
  ASSERT_TRUE(id_a && id_b);
  EXPECT_NE(*id_a, *id_b);

  // follow(closest in front) picked A (the closer one), and the guide state reports it from then on.
  ASSERT_TRUE(guide_reply.has_value());
  EXPECT_EQ(*guide_reply, *id_a);
  int tracking = 0;
  for (int k = select_at + 2; k < steps; ++k) {
    const auto* msg = heardAt(heard.guide, 100.0 + k * dt);
    if (!msg) continue;
    EXPECT_EQ(msg->track_id, static_cast<int32_t>(*id_a));
    tracking += msg->state == pmsg::GuideState_Constants::TRACKING;
  }
  EXPECT_GE(tracking, 10);

  // scan_filtered (mask.people: guide): the beam towards A's centre is NaN, the beam towards B's is the raw return.
  int checked = 0;
  for (int k = select_at + 5; k < steps; ++k) {
    const double t = 100.0 + k * dt;
    const auto* msg = heardAt(heard.masked, t);
    if (!msg) continue;
    const auto& raw = sent[k];
    ASSERT_EQ(msg->ranges.size(), raw.ranges.size());
    const auto robot = world.laserPose(k * dt);
    auto beamTo = [&](const Eigen::Vector2d& p) {
      const Eigen::Vector2d local = robot.inverseTransform(p);
      return static_cast<std::size_t>(std::lround((std::atan2(local.y(), local.x()) - raw.angle_min) / raw.angle_increment));
    };
    const std::size_t ba = beamTo(world.personA(k * dt)), bb = beamTo(world.personB(k * dt));
    EXPECT_TRUE(std::isnan(msg->ranges[ba])) << "guide not masked at scan " << k;
    EXPECT_EQ(msg->ranges[bb], raw.ranges[bb]) << "a non-guide was masked at scan " << k;
    std::size_t masked = 0;
    for (std::size_t i = 0; i < raw.ranges.size(); ++i) masked += std::isnan(msg->ranges[i]) && !std::isnan(raw.ranges[i]);
    EXPECT_GT(masked, 5u);
    EXPECT_LT(masked, 120u) << "more than the guide's circle masked";
    ++checked;
  }
  EXPECT_GE(checked, 10);

}

// Without TF the component skips scans for tf_timeout seconds of scan time, then uses sensor_x/y/yaw.
TEST(PeopleTrackerComponent, LaserMountFallsBackToParametersWhenNoTfArrives) {
  World world;
  FallbackMountRig rig;
  ASSERT_NO_FATAL_FAILURE(rig.start("people_container3", world, 0.5));
  const double dt = 1.0 / 15.0;
  const int steps = 30;
  rig.play(world, 200.0, steps, dt);
  rig.stop();
  Heard& heard = rig.heard;
  std::lock_guard l(heard.mu);
  int matched = 0, processed = 0;
  for (int k = 0; k < steps; ++k) {
    const auto* msg = heardAt(heard.tracks, 200.0 + k * dt);
    if (k * dt < 0.5 - 1e-9) {
      EXPECT_EQ(msg, nullptr) << "scan " << k << " processed while waiting for TF";
      continue;
    }
    ASSERT_NE(msg, nullptr) << "scan " << k << " not processed after the TF timeout";
    ++processed;
    if (k >= 15 && trackNear(*msg, world.personA(k * dt), 0.35)) ++matched;
  }
  EXPECT_GE(processed, 20);
  EXPECT_GE(matched, 13) << "person A not tracked at its odometry-frame position with the fallback mount";
}

// Odometry lagging the scans by more than odom_tolerance (0.2 s; here 4 scans = 0.27 s): the scans wait for it
// (odom_queue) and are all processed as it arrives; with odom_queue 0 they are ignored as before.
TEST(PeopleTrackerComponent, ScansWaitForOdometryThatLagsBehindThem) {
  // processed: scans 5-29 answered; lagging: of them, scans 8-29, whose odometry is >= 0.27 s old when they arrive
  // (scans 5-7 are within odom_tolerance of the odometry of scan 4, extrapolated).
  auto run = [](int64_t queue, int& processed, int& lagging, int& matched) {
    World world;
    FallbackMountRig rig;
    ASSERT_NO_FATAL_FAILURE(rig.start(queue > 0 ? "people_container9" : "people_container10", world, 0.0,
                                      {{"odom_queue", queue}}));
    const double dt = 1.0 / 15.0, t0 = 300.0;
    rig.play(world, t0, 5, dt);  // odometry in step with the scans: tracking starts
    constexpr int kLag = 4, kEnd = 30;
    auto sendOdom = [&](int k) {
      auto odom = world.odomAt(k * dt);
      odom.header.stamp = stampOf(t0 + k * dt);
      rig.odom_pub->publish(odom);
    };
    for (int k = 5; k < kEnd; ++k) {
      pt::LaserScan s = world.scanAt(k * dt, dt);
      s.stamp = t0 + k * dt;
      rig.scan_pub->publish(toMsg(s));
      std::this_thread::sleep_for(30ms);  // best-effort scans (keep last 5): do not outrun the reader's history
      if (k - kLag >= 5) sendOdom(k - kLag);
    }
    for (int k = kEnd - kLag; k < kEnd; ++k) sendOdom(k);
    waitFor([&] {
      std::lock_guard l(rig.heard.mu);
      return heardAt(rig.heard.tracks, t0 + (kEnd - 1) * dt) != nullptr;
    }, 5s);
    std::this_thread::sleep_for(200ms);
    rig.stop();
    std::lock_guard l(rig.heard.mu);
    for (int k = 5; k < kEnd; ++k) {
      const auto* msg = heardAt(rig.heard.tracks, t0 + k * dt);
      if (!msg) continue;
      ++processed;
      if (k >= 8) ++lagging;
      if (trackNear(*msg, world.personA(k * dt), 0.35)) ++matched;
    }
  };
  int processed = 0, lagging = 0, matched = 0;
  run(10, processed, lagging, matched);
  EXPECT_EQ(processed, 25) << "every scan waits for its odometry and is processed";
  EXPECT_GE(matched, 22) << "person A tracked at its odometry-frame position from the held scans";
  int processed0 = 0, lagging0 = 0, matched0 = 0;
  run(0, processed0, lagging0, matched0);
  EXPECT_EQ(lagging0, 0) << "odom_queue 0: scans whose odometry lags beyond odom_tolerance are ignored";
}

TEST(PeopleTrackerComponent, MalformedScansAreSkippedAndTheComponentKeepsRunning) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "people_container2", loader);
  cairn::LoadRequest req{"cairn_people_tracking::PeopleTracker", "people_tracker"};
  req.parameters["use_odom"] = false;  // tracks in the laser frame
  const auto loaded = mgr.load(req);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  Spinner spinner(exec);

  auto sim_ctx = cairn::Context::create();
  cairn::Executor sim_exec;
  cairn::NodeOptions o("sim", &sim_exec);
  o.context = sim_ctx;
  o.start_parameter_services = false;
  cairn::Node sim(o);
  Heard heard;
  // Reliable scans here, so that "no output for a bad scan" is not confused with a lost scan.
  auto scan_pub = sim.create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS{});
  auto tracks_sub = sim.create_subscription<pmsg::TrackedPersons>("people/tracks", cairn::QoS{}, [&](const pmsg::TrackedPersons& m) {
    std::lock_guard l(heard.mu);
    heard.tracks[key(m.header.stamp)] = m;
  });
  Spinner sim_spinner(sim_exec);
  ASSERT_TRUE(waitFor([&] { return scan_pub->inter_process_subscription_count() > 0; }, 20s));
  auto received = [&](double t) {
    std::lock_guard l(heard.mu);
    return heardAt(heard.tracks, t) != nullptr;
  };

  World world;
  world.robot_v = 0.0;
  world.robot_w = 1e-9;
  const double dt = 1.0 / 15.0;
  double t = 50.0;
  // a good scan first (and the tracks writer discovered)
  auto good = [&](double stamp) {
    pt::LaserScan s = world.scanAt(stamp - 50.0, dt);
    s.stamp = stamp;
    return toMsg(s);
  };
  ASSERT_TRUE(waitFor([&] {
    scan_pub->publish(good(t));
    return waitFor([&] { return received(t); }, 300ms) || (t += dt, false);
  }, 20s));

  std::vector<std::pair<std::string, sensor_msgs::msg::LaserScan>> bad;
  auto m = good(t + dt);
  m.angle_max += 0.5f;  // metadata describe ~90 more beams than there are ranges
  bad.emplace_back("mismatched angle metadata", m);
  m = good(t + 2 * dt);
  m.ranges.clear();
  m.angle_max = m.angle_min;
  bad.emplace_back("zero-length scan", m);
  m = good(t + 3 * dt);
  m.angle_increment = std::numeric_limits<float>::quiet_NaN();
  bad.emplace_back("NaN angle increment", m);
  m = good(t + 4 * dt);
  m.intensities.assign(10, 1.0f);
  bad.emplace_back("intensities of the wrong size", m);
  for (const auto& [what, msg] : bad) scan_pub->publish(msg);

  // NaN and inf ranges inside a well-formed scan are "no return": processed.
  auto holes = good(t + 5 * dt);
  for (std::size_t i = 0; i < holes.ranges.size(); i += 7) holes.ranges[i] = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 3; i < holes.ranges.size(); i += 11) holes.ranges[i] = std::numeric_limits<float>::infinity();
  scan_pub->publish(holes);
  ASSERT_TRUE(waitFor([&] { return received(t + 5 * dt); }, 10s)) << "scan with NaN/inf ranges not processed";
  // Time going backwards: processed (the tracker resets), and later scans too.
  const double back = t - 10.0;
  scan_pub->publish(good(back));
  ASSERT_TRUE(waitFor([&] { return received(back); }, 10s)) << "scan after time went backwards not processed";
  scan_pub->publish(good(back + dt));
  ASSERT_TRUE(waitFor([&] { return received(back + dt); }, 10s));
  sim_spinner.stop();
  spinner.stop();

  std::lock_guard l(heard.mu);
  // One reliable writer keeps its order: a bad scan that produced output would have arrived before `holes`.
  for (std::size_t i = 0; i < bad.size(); ++i)
    EXPECT_EQ(heard.tracks.count(key(bad[i].second.header.stamp)), 0u) << bad[i].first << " was not rejected";
  const auto* after_reset = heardAt(heard.tracks, back);
  ASSERT_NE(after_reset, nullptr) << "the scan after the time jump was not processed";
  EXPECT_EQ(after_reset->header.frame_id, "laser");
  EXPECT_TRUE(after_reset->tracks.empty()) << "a reset tracker has no confirmed tracks";

}

// Two leg-like posts 0.25 m apart stand still 5 m ahead: without a static map the tracker reports them as a
// person; with `static_map.topic` and a latched OccupancyGrid (in the odometry frame, grid origin rotated by 90
// degrees so the origin pose is honoured) whose cells cover them they are dropped, and the walking person is
// tracked either way.
TEST(PeopleTrackerComponent, StaticMapDropsLegsOnMappedCells) {
  const std::vector<Eigen::Vector2d> posts = {{5.0, 2.5}, {5.0, 2.75}};
  auto run = [&](bool with_map, int& on_posts, int& on_a) {
    World world;
    world.static_legs = posts;
    FallbackMountRig rig;
    std::map<std::string, cairn::ParameterValue> extra;
    if (with_map) extra["static_map.topic"] = std::string("map");
    ASSERT_NO_FATAL_FAILURE(rig.start(with_map ? "people_container5" : "people_container4", world, 0.2, extra));
    // The map's writer lives until the run ends: a latched sample goes with its writer, and under load the
    // component may match the writer before it has received the sample.
    decltype(rig.sim->create_publisher<nav_msgs::msg::OccupancyGrid>("map", cairn::QoS::latched())) map_pub;
    if (with_map) {
      map_pub = rig.sim->create_publisher<nav_msgs::msg::OccupancyGrid>("map", cairn::QoS::latched());
      // 40 x 40 cells of 5 cm; origin at (6, 2) turned by +90 deg: cell (i, j) centre = (6 - (j + 0.5) r, 2 + (i + 0.5) r).
      nav_msgs::msg::OccupancyGrid grid;
      grid.header.frame_id = "odom";
      grid.info.resolution = 0.05F;
      grid.info.width = grid.info.height = 40;
      grid.info.origin.position.x = 6.0;
      grid.info.origin.position.y = 2.0;
      grid.info.origin.orientation.z = std::sin(M_PI / 4);
      grid.info.origin.orientation.w = std::cos(M_PI / 4);
      grid.data.assign(40 * 40, 0);
      for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i) {
          const Eigen::Vector2d c(6.0 - (j + 0.5) * 0.05, 2.0 + (i + 0.5) * 0.05);
          for (const Eigen::Vector2d& p : posts)
            if ((c - p).norm() <= 0.07) grid.data[static_cast<std::size_t>(j * 40 + i)] = 100;
        }
      map_pub->publish(grid);
      ASSERT_TRUE(waitFor([&] { return map_pub->inter_process_subscription_count() > 0; }, 20s));
    }
    const double dt = 1.0 / 15.0;
    const int steps = 45;
    rig.play(world, 300.0, steps, dt);
    rig.stop();
    Heard& heard = rig.heard;
    std::lock_guard l(heard.mu);
    for (int k = 15; k < steps; ++k) {
      const auto* msg = heardAt(heard.tracks, 300.0 + k * dt);
      if (!msg) continue;
      for (const auto& tr : msg->tracks)
        if ((Eigen::Vector2d(tr.position.x, tr.position.y) - 0.5 * (posts[0] + posts[1])).norm() < 0.35) ++on_posts;
      if (trackNear(*msg, world.personA(k * dt), 0.35)) ++on_a;
    }
  };
  int posts_without = 0, a_without = 0, posts_with = 0, a_with = 0;
  run(false, posts_without, a_without);
  run(true, posts_with, a_with);
  EXPECT_GE(posts_without, 20) << "the posts should look like a person without the map (else the test shows nothing)";
  EXPECT_EQ(posts_with, 0) << "legs on mapped cells must not make a person";
  EXPECT_GE(a_without, 25);
  EXPECT_GE(a_with, 25);
}

// fusion.topic: person detections of another source (here a "camera" in the robot's base frame, which moves)
// are fused with the legs; a person the laser cannot see (standing behind nothing the scan shows: it is simply
// not rendered) is tracked from them alone, at its odometry-frame position. Without the parameter: no track.
TEST(PeopleTrackerComponent, OtherSourceDetectionsAreFusedAndTracked) {
  const Eigen::Vector2d hidden(3.0, -3.0);  // odometry frame
  const double dt = 1.0 / 15.0;
  constexpr int steps = 45;
  // lag: the other source's message for scan k is sent with scan k + lag (a camera pipeline slower than the laser,
  // or its messages reaching the executor late under load); wait: fusion.wait (< 0: the default); silent_from: the
  // source sends nothing for scans from this one on (-1: never); back_at: with the message for this scan the source
  // also sends one stamped 100 s earlier (a restarted clock; -1: never). Counts, over scans 15-44: scans answered,
  // tracks on the other source's person (and over the last 10 scans only), tracks on person A.
  struct Counts {
    int answered = 0, on_hidden = 0, on_hidden_last10 = 0, on_a = 0;
  };
  auto run = [&](const std::string& container, bool with_fusion, int lag, double wait, int silent_from = -1,
                 int back_at = -1) {
    Counts c;
    if (silent_from < 0) silent_from = steps;
    World world;
    FallbackMountRig rig;
    std::map<std::string, cairn::ParameterValue> extra;
    if (with_fusion) extra["fusion.topic"] = std::string("people/camera_detections");
    if (wait >= 0.0) extra["fusion.wait"] = wait;
    rig.start(container, world, 0.2, extra);
    if (::testing::Test::HasFatalFailure()) return c;
    auto cam_pub = rig.sim->create_publisher<pmsg::PersonDetections>("people/camera_detections", cairn::QoS{});
    if (with_fusion && !waitFor([&] { return cam_pub->inter_process_subscription_count() > 0; }, 20s)) {
      ADD_FAILURE() << container << ": the component did not subscribe to the other source";
      return c;
    }
    auto send = [&](int k, double shift = 0.0) {
      pmsg::PersonDetections m;
      m.header.stamp = stampOf(400.0 + k * dt + shift);
      m.header.frame_id = "base_footprint";
      pmsg::PersonDetection d;
      const Eigen::Vector2d p = world.robot(k * dt).inverseTransform(hidden);
      d.position.x = p.x();
      d.position.y = p.y();
      d.covariance = {0.04, 0.0, 0.0, 0.01};
      d.confidence = 0.9;
      d.source = 1;
      m.detections.push_back(d);
      pmsg::PersonDetection bad = d;  // skipped with a warning, the message's other detections still count
      bad.covariance = {0.04, 0.0, 0.0, -1.0};
      m.detections.push_back(bad);
      cam_pub->publish(m);
      cam_pub->wait_for_all_acked(5s);  // in the component's reader before the scan (as the odometry in play())
    };
    const bool waits = lag > 0 && wait != 0.0;
    // Which scans are answered once scan k is sent: a scan waits for its own message (sent with scan k + lag).
    // After the source falls silent a scan waits until it is fusion.wait (0.5 s, 7.5 scans) behind the newest
    // one, and not at all once the newest message is more than fusion.wait behind it.
    auto answered_through = [&](int k) {
      if (!waits) return k;
      if (k < silent_from + lag) return k - lag;
      const int last_message = silent_from - 1;
      const int first_unheld = last_message + 8;  // 8 scans (0.53 s) after the last message: it does not wait
      // Scans before it wait 8 scans each; the last of them goes with scan first_unheld + 7, and the rest at once.
      return k >= first_unheld + 7 ? k : std::max(last_message, k - 8);
    };
    rig.play(world, 400.0, steps, dt, [&](int k, double) {
      if (k < lag || k - lag >= silent_from) return;
      send(k - lag);
      if (k - lag == back_at) send(k - lag, -100.0);
    }, answered_through);
    // The source catches up: the waiting scans go through.
    for (int k = steps - lag; k < std::min(steps, silent_from); ++k) send(k);
    if (lag > 0) {
      waitFor([&] {
        std::lock_guard l(rig.heard.mu);
        return heardAt(rig.heard.tracks, 400.0 + (steps - 1) * dt) != nullptr;
      }, waits ? 5s : 500ms);
    }
    rig.stop();
    Heard& heard = rig.heard;
    std::lock_guard l(heard.mu);
    for (int k = 15; k < steps; ++k) {
      const auto* msg = heardAt(heard.tracks, 400.0 + k * dt);
      if (!msg) continue;
      ++c.answered;
      if (trackNear(*msg, hidden, 0.3)) {
        ++c.on_hidden;
        if (k >= steps - 10) ++c.on_hidden_last10;
      }
      if (trackNear(*msg, world.personA(k * dt), 0.35)) ++c.on_a;
    }
    return c;
  };
  const Counts without = run("people_container6", false, 0, -1.0);
  const Counts with = run("people_container7", true, 0, -1.0);
  EXPECT_EQ(without.on_hidden, 0) << "nothing on the laser is there";
  EXPECT_GE(with.on_hidden, 25) << "the other source's person must be tracked at its odometry-frame position";
  EXPECT_GE(without.on_a, 25);
  EXPECT_GE(with.on_a, 25);
  // The source lags three scans (0.2 s, more than fusion.max_age): the scans wait for it (fusion.wait 0.5 s) and
  // each is fused with its own message; without waiting every message is too old when its scan is processed.
  const Counts lagged = run("people_container7l", true, 3, -1.0);
  const Counts no_wait = run("people_container7n", true, 3, 0.0);
  EXPECT_EQ(lagged.answered, 30);
  EXPECT_GE(lagged.on_hidden, 25) << "scans must wait for the lagging source";
  EXPECT_GE(lagged.on_a, 25);
  EXPECT_EQ(no_wait.answered, 30);
  EXPECT_EQ(no_wait.on_hidden, 0) << "fusion.wait 0: the lagging messages are stale";
  EXPECT_GE(no_wait.on_a, 25);
  // The lagging source sends nothing for scans 20 on: the scans wait at most fusion.wait and then go on without it;
  // every scan is still answered and person A still tracked, the other source's person is lost.
  const Counts silent = run("people_container7s", true, 3, -1.0, 20);
  EXPECT_EQ(silent.answered, 30) << "a silent source must not hold the scans";
  EXPECT_GE(silent.on_a, 25);
  EXPECT_LT(silent.on_hidden, 25);
  // A message 100 s in the past is taken as a restart of the source: the queue is dropped with a warning, the next
  // scans (their messages still to come) no longer wait and go on without them — three, or more when the executor
  // takes scans before messages under load — and once a message in order has come every scan waits for its own
  // again: nothing stalls, and the other source's person is tracked again at the end.
  const Counts back = run("people_container7b", true, 3, -1.0, -1, 25);
  EXPECT_EQ(back.answered, 30);
  EXPECT_GE(back.on_hidden_last10, 9);
  EXPECT_GE(back.on_a, 25);
}

// detector.*, guide.* and mask.* change at run time over the parameter services (`cairn param set`): here the
// detection range shrinks to 0.1 m mid-run and person A's track goes; a bad choice and a read-only parameter are
// refused with a reason, and the component keeps running.
TEST(PeopleTrackerComponent, DetectorParametersChangeAtRunTime) {
  World world;
  FallbackMountRig rig;
  ASSERT_NO_FATAL_FAILURE(rig.start("people_container8", world, 0.2));
  std::shared_ptr<cairn::Subscription<sensor_msgs::msg::LaserScan>> masked_sub =
      rig.sim->create_subscription<sensor_msgs::msg::LaserScan>("scan_filtered", cairn::QoS::sensor_data(), [&](const sensor_msgs::msg::LaserScan& m) {
        std::lock_guard l(rig.heard.mu);
        rig.heard.masked[key(m.header.stamp)] = m;
      });
  ASSERT_TRUE(waitFor([&] { return masked_sub->publisher_count_inter_process() > 0; }, 20s));
  auto set = rig.sim->create_client<rcl_interfaces::srv::SetParameters_Request, rcl_interfaces::srv::SetParameters_Response>(
      "/people_tracker/set_parameters");
  auto request = [](const std::string& name, const cairn::ParameterValue& v) {
    rcl_interfaces::srv::SetParameters_Request r;
    rcl_interfaces::msg::Parameter p;
    p.name = name;
    p.value = cairn::to_parameter_msg(v);
    r.parameters.push_back(p);
    return r;
  };
  // Phases: mask.people all (default) until scan `unmask`, then none; detector.max_range 0.1 m from `shrink`.
  const double dt = 1.0 / 15.0;
  const int steps = 75, unmask = 30, shrink = 50;
  std::optional<rcl_interfaces::srv::SetParameters_Response> bad_choice, read_only, none, range;
  rig.play(world, 500.0, steps, dt, [&](int k, double) {
    if (k == unmask) {
      bad_choice = set->call(request("mask.people", std::string("everyone")), 10s);
      read_only = set->call(request("tracker.process_noise", 1.0), 10s);
      none = set->call(request("mask.people", std::string("none")), 10s);
    }
    if (k == shrink) range = set->call(request("detector.max_range", 0.1), 10s);
  });
  rig.stop();
  ASSERT_TRUE(bad_choice && read_only && none && range);
  ASSERT_EQ(bad_choice->results.size(), 1u);
  EXPECT_FALSE(bad_choice->results[0].successful);
  EXPECT_NE(bad_choice->results[0].reason.find("must be all, guide or none"), std::string::npos) << bad_choice->results[0].reason;
  ASSERT_EQ(read_only->results.size(), 1u);
  EXPECT_FALSE(read_only->results[0].successful);
  ASSERT_EQ(none->results.size(), 1u);
  EXPECT_TRUE(none->results[0].successful) << none->results[0].reason;
  ASSERT_EQ(range->results.size(), 1u);
  EXPECT_TRUE(range->results[0].successful) << range->results[0].reason;
  Heard& heard = rig.heard;
  std::lock_guard l(heard.mu);
  // Beams with a return in the sent scan that scan_filtered set to NaN.
  auto maskedBeams = [&](double t) -> int {
    const auto* out = heardAt(heard.masked, t);
    const auto* in = heardAt(rig.sent, t);
    if (!out || !in || out->ranges.size() != in->ranges.size()) return -1;
    int n = 0;
    for (std::size_t i = 0; i < in->ranges.size(); ++i) n += std::isfinite(in->ranges[i]) && !std::isfinite(out->ranges[i]);
    return n;
  };
  int tracked = 0, masking = 0, tracked_unmasked = 0, unmasked_beams = 0, after = 0, processed_after = 0;
  for (int k = 15; k < steps; ++k) {
    const double t = 500.0 + k * dt;
    const auto* msg = heardAt(heard.tracks, t);
    if (!msg) continue;
    const bool on_a = trackNear(*msg, world.personA(k * dt), 0.35).has_value();
    const int m = maskedBeams(t);  // -1: scan_filtered not heard (best effort)
    if (k < unmask && on_a && m >= 0) {
      ++tracked;
      masking += m > 0;
    }
    if (k >= unmask + 1 && k < shrink && on_a && m >= 0) {
      ++tracked_unmasked;
      unmasked_beams += m;
    }
    if (k >= shrink + 10) {
      after += on_a;
      ++processed_after;
    }
  }
  EXPECT_GE(tracked, 12) << "person A tracked before the changes";
  EXPECT_GE(masking, tracked - 2) << "mask.people all: A's beams hidden in scan_filtered";
  EXPECT_GE(tracked_unmasked, 12) << "mask.people none leaves tracking alone";
  EXPECT_EQ(unmasked_beams, 0) << "mask.people none: scan_filtered is the scan";
  EXPECT_GE(processed_after, 10) << "scans still processed after the range change";
  EXPECT_EQ(after, 0) << "no legs beyond 0.1 m after the change, so no track on person A";
}

// The guide stays TRACKING through a leg dropout shorter than guide.lost_timeout (1 s): Person Lost is for a
// guide gone that long (Yuan §2.2.1). The guide tracker used to see only the published tracks, which drop a track
// after 0.25 s of coasting, so every short dropout was "lost: track deleted" and lost_timeout had no effect.
TEST(PeopleTrackerComponent, GuideSurvivesAShortDropout) {
  World world;
  std::map<int64_t, pmsg::GuideState> guide;  // before the rig: written by its spinning thread until rig.stop()
  FallbackMountRig rig;
  ASSERT_NO_FATAL_FAILURE(rig.start("people_container9", world, 0.2));
  auto guide_sub = rig.sim->create_subscription<pmsg::GuideState>("people/guide", cairn::QoS{}, [&](const pmsg::GuideState& m) {
    std::lock_guard l(rig.heard.mu);
    guide[key(m.header.stamp)] = m;
  });
  auto follow = rig.sim->create_client<psrv::Follow_Request, psrv::Follow_Response>("people/follow");
  ASSERT_TRUE(waitFor([&] { return guide_sub->publisher_count_inter_process() > 0; }, 20s));
  const double dt = 1.0 / 15.0;
  const int steps = 60, select_at = 20;
  world.hide_a_from = 35 * dt;  // 7 scans (0.47 s): longer than publish_coast_time, shorter than lost_timeout
  world.hide_a_to = 42 * dt;
  std::optional<psrv::Follow_Response> chosen;
  rig.play(world, 300.0, steps, dt, [&](int k, double) {
    if (k != select_at) return;
    psrv::Follow_Request rq;
    rq.command = psrv::Follow_Request_Constants::CLOSEST_IN_FRONT;
    chosen = follow->call(rq, 20s);
  });
  rig.stop();
  ASSERT_TRUE(chosen && chosen->success) << (chosen ? chosen->message : "no reply");
  std::lock_guard l(rig.heard.mu);
  int tracking = 0, during = 0;
  for (int k = select_at + 2; k < steps; ++k) {
    const auto* msg = heardAt(guide, 300.0 + k * dt);
    if (!msg) continue;
    EXPECT_EQ(msg->state, pmsg::GuideState_Constants::TRACKING) << "scan " << k << ": " << msg->event;
    EXPECT_EQ(msg->track_id, chosen->track_id) << "scan " << k;
    tracking += msg->state == pmsg::GuideState_Constants::TRACKING;
    during += k >= 35 && k < 42;
  }
  EXPECT_GE(tracking, 25);
  EXPECT_GE(during, 5) << "the dropout's scans were heard";
}

namespace {
std::string launchError(const std::string& params) {
  return cairn::launch_spec_error(
        "containers:\n  - name: c\n    components:\n      - class: cairn_people_tracking::PeopleTracker\n"
        "        params: " + params + "\n",
      "people.yaml");
}
}  // namespace

TEST(PeopleTrackerComponent, LaunchSpecValidatesItsParameters) {
  std::string e0;
  EXPECT_EQ(launchError("{tracker.association: jpda, tracker.process_noise: 0.8, guide.auto_reacquire: false, "
                        "segmentation.min_points: 4, mask.people: all, model_file: leg_svm_stuede5.yml, "
                        "tracker.leg_spread_sigma: 0.25, tracker.leg_gate_chi2: 6.0, tracker.reid_window: 0.0, "
                        "tracker.occluded_coast_time: 0.5, tracker.free_space_delete_scans: 3}"),
            "");
  EXPECT_EQ(launchError("{motion.window: 0.0, motion.min_age: 0.2, motion.margin: 0.1, detector.moving_fraction: 0.7, "
                        "detector.moving_track_leg_confidence: 0.1, detector.moving_min_leg_confidence: 0.4}"),
            "");
  e0 = launchError("{motion.window: -1.0}");
  EXPECT_NE(e0.find("motion.window"), std::string::npos) << e0;
  EXPECT_EQ(launchError("{motion.memory: 120.0, motion.memory_resolution: 0.05, motion.memory_size: 30.0, "
                        "motion.memory_surface_gap: 0.5, detector.crossed_track_leg_confidence: 0.1}"),
            "");
  e0 = launchError("{motion.memory_size: 500.0}");
  EXPECT_NE(e0.find("motion.memory_size"), std::string::npos) << e0;
  e0 = launchError("{motion.memory: -1.0}");
  EXPECT_NE(e0.find("motion.memory"), std::string::npos) << e0;
  e0 = launchError("{detector.crossed_track_leg_confidence: 2.0}");
  EXPECT_NE(e0.find("detector.crossed_track_leg_confidence"), std::string::npos) << e0;
  e0 = launchError("{detector.moving_fraction: 1.5}");
  EXPECT_NE(e0.find("detector.moving_fraction"), std::string::npos) << e0;
  e0 = launchError("{tracker.leg_gate_chi2: 0.0}");
  EXPECT_NE(e0.find("tracker.leg_gate_chi2"), std::string::npos) << e0;
  e0 = launchError("{tracker.leg_spread_sigma: -0.1}");
  EXPECT_NE(e0.find("tracker.leg_spread_sigma"), std::string::npos) << e0;
  EXPECT_EQ(launchError("{tracker.process_noise: fast}"),
            "people.yaml:5: params: /people_tracker: parameter 'tracker.process_noise' expects double, got string (\"fast\")");
  auto e = launchError("{detector.min_leg_confidence: 1.5}");
  EXPECT_NE(e.find("detector.min_leg_confidence"), std::string::npos) << e;
  EXPECT_EQ(e.rfind("people.yaml:5:", 0), 0u) << e;
  e = launchError("{segmentation.min_points: 2.5}");
  EXPECT_NE(e.find("segmentation.min_points"), std::string::npos) << e;
  e = launchError("{tracker.jpda_max_events: 0}");
  EXPECT_NE(e.find("tracker.jpda_max_events"), std::string::npos) << e;
  e = launchError("{use_odom: 1}");
  EXPECT_NE(e.find("parameter 'use_odom' expects bool"), std::string::npos) << e;
  e = launchError("{tracker.association: kalman}");
  EXPECT_NE(e.find("'tracker.association' must be gnn or jpda, got 'kalman'"), std::string::npos) << e;
  EXPECT_EQ(launchError("{mask.mode: tangents}"), "");
  e = launchError("{mask.mode: everything}");
  EXPECT_NE(e.find("'mask.mode' must be tangents or inside, got 'everything'"), std::string::npos) << e;
  e = launchError("{model_file: no_such_model.yml}");
  EXPECT_NE(e.find("model_file: 'no_such_model.yml' not found"), std::string::npos) << e;
  e = launchError("{tracker.no_such_param: 1}");
  EXPECT_NE(e.find("tracker.no_such_param"), std::string::npos) << e;
}

// A free-space memory grid too large for its cell (200 m at 0.02 m: 10 000 cells per side, 800 MB) passes each
// parameter's range but is refused at load, with the reason.
TEST(PeopleTrackerComponent, RefusesAFreeSpaceMemoryGridTooLargeForItsCell) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "people_container", loader);
  cairn::LoadRequest req{"cairn_people_tracking::PeopleTracker", "people_tracker"};
  req.parameters["motion.memory_size"] = 200.0;
  req.parameters["motion.memory_resolution"] = 0.02;
  const auto loaded = mgr.load(req);
  EXPECT_FALSE(loaded.ok);
  EXPECT_NE(loaded.error.find("free-space memory (motion.memory_*)"), std::string::npos) << loaded.error;
  req.parameters["motion.memory_resolution"] = 0.1;
  const auto fine = mgr.load(req);
  EXPECT_TRUE(fine.ok) << fine.error;
}
