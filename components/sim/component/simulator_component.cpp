// cairn_sim::Simulator — the runtime adapter of the simulator core (cairn/sim/simulator.hpp): cmd_vel in;
// scan, odom, /tf (odom -> base_link), ground_truth, people/ground_truth and /clock out. Thin: parameter
// plumbing, message conversion and a wall timer that advances the core to `real_time_factor` × elapsed wall
// time. All simulation (kinematics, laser, odometry noise, people, routes) is the core's.
#include <algorithm>
#include <functional>
#include <optional>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cairn/component.hpp"
#include "cairn/sim/simulator.hpp"
#include "cairn_sim_msgs/msg/PersonArray.hpp"
#include "cairn_sim_msgs/srv/NavigateTo.hpp"
#include "convert.hpp"
#include "geometry_msgs/msg/Twist.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "rosgraph_msgs/msg/Clock.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

namespace cairn_sim {

namespace sim = cairn::sim;
namespace cv = cairn_sim::convert;

class Simulator : public cairn::Node {
 public:
  explicit Simulator(const cairn::NodeOptions& o) : cairn::Node(o) {
    using D = cairn::ParameterDescriptor;
    constexpr double kDeg = std::numbers::pi / 180.0;
    const std::string world_param = declare_parameter<std::string>(
        "world", "office", D{"shipped world name (office, apartment, warehouse) or path to a world YAML", {}, {}, true});
    sim::SimConfig cfg;
    cfg.seed = static_cast<std::uint64_t>(declare_parameter<int64_t>(
        "seed", 1, D{"seed of all random streams (laser, odometry, people); same seed + world = same scans", 0.0, 9.0e15, true}));
    rtf_ = declare_parameter<double>("real_time_factor", 1.0, D{"sim seconds per wall second (> 1: faster than real time)", 0.01, 1000.0, true});
    const double tick_hz = declare_parameter<double>("tick_rate", 100.0, D{"Hz, wall timer that advances the simulation", 1.0, 1000.0, true});
    cfg.physics_dt = declare_parameter<double>("physics_dt", cfg.physics_dt, D{"s, fixed physics step", 0.001, 0.1, true});
    cfg.odom_rate = declare_parameter<double>("odom_rate", cfg.odom_rate, D{"Hz (sim time), odom, ground_truth and /tf", 1.0, 1000.0, true});
    people_rate_ = declare_parameter<double>("people.rate", 10.0, D{"Hz (sim time), people/ground_truth", 0.1, 1000.0, true});

    // Frames (REP 105).
    map_frame_ = declare_parameter<std::string>("map_frame", "map", D{"frame of ground_truth and people/ground_truth", {}, {}, true});
    odom_frame_ = declare_parameter<std::string>("odom_frame", "odom", D{"frame of odom", {}, {}, true});
    base_frame_ = declare_parameter<std::string>("base_frame", "base_link", D{"robot frame (URDF root link)", {}, {}, true});
    publish_tf_ = declare_parameter<bool>("publish_tf", true, D{"odom -> base_link on /tf", {}, {}, true});
    publish_map_tf_ = declare_parameter<bool>(
        "publish_map_tf", false, D{"map -> odom on /tf from ground truth (perfect localization; normally SLAM's job)", {}, {}, true});

    // Laser (LaserConfig; defaults match urdf/cairn_service_robot.urdf).
    auto& l = cfg.laser;
    l.frame_id = declare_parameter<std::string>("laser.frame_id", l.frame_id, D{"frame of scan (URDF link)", {}, {}, true});
    l.mount.x = declare_parameter<double>("laser.x", l.mount.x, D{"m, laser in base_link (must match the URDF)", -10.0, 10.0, true});
    l.mount.y = declare_parameter<double>("laser.y", l.mount.y, D{"m, laser in base_link", -10.0, 10.0, true});
    l.mount.theta = declare_parameter<double>("laser.yaw", l.mount.theta, D{"rad, laser in base_link", -std::numbers::pi, std::numbers::pi, true});
    l.fov = kDeg * declare_parameter<double>("laser.fov_deg", 360.0, D{"deg, field of view (180, 270, 360)", 1.0, 360.0, true});
    l.resolution = kDeg * declare_parameter<double>("laser.resolution_deg", 0.5, D{"deg between beams", 0.05, 10.0, true});
    l.rate = declare_parameter<double>("laser.rate", l.rate, D{"Hz (sim time), scans", 0.1, 200.0, true});
    l.range_min = declare_parameter<double>("laser.range_min", l.range_min, D{"m", 0.0, 10.0, true});
    l.range_max = declare_parameter<double>("laser.range_max", l.range_max, D{"m", 0.1, 200.0, true});
    l.noise_sigma = declare_parameter<double>("laser.noise_sigma", l.noise_sigma, D{"m, Gaussian range noise", 0.0, 1.0, true});
    l.outlier_prob = declare_parameter<double>("laser.outlier_prob", l.outlier_prob, D{"per beam: short reading", 0.0, 1.0, true});
    l.dropout_prob = declare_parameter<double>("laser.dropout_prob", l.dropout_prob, D{"per beam: no return (+inf)", 0.0, 1.0, true});
    l.binary_intensity = declare_parameter<bool>("laser.binary_intensity", l.binary_intensity, D{"intensity in {0, 1} (Dörr §4.4.1)", {}, {}, true});
    l.binary_threshold = declare_parameter<double>("laser.binary_threshold", l.binary_threshold, D{"reflectivity -> 1 at or above", 0.0, 1.0, true});
    l.intensity_scale = declare_parameter<double>("laser.intensity_scale", l.intensity_scale, D{"intensity = scale × reflectivity", 0.0, 1.0e6, true});
    l.motion_distortion = declare_parameter<bool>("laser.motion_distortion", l.motion_distortion, D{"beam i from the pose at stamp + i·time_increment", {}, {}, true});

    // Odometry error (OdometryNoiseConfig; ≈1 % of the distance: Dörr §6.2.2).
    auto& on = cfg.odometry;
    on.scale_error = declare_parameter<double>("odometry.scale_error", on.scale_error, D{"systematic relative distance error", -0.5, 0.5, true});
    on.rotation_scale_error = declare_parameter<double>("odometry.rotation_scale_error", on.rotation_scale_error, D{"systematic relative rotation error", -0.5, 0.5, true});
    on.heading_drift = declare_parameter<double>("odometry.heading_drift", on.heading_drift, D{"rad per metre", -1.0, 1.0, true});
    on.sigma_trans = declare_parameter<double>("odometry.sigma_trans", on.sigma_trans, D{"m/√m", 0.0, 1.0, true});
    on.sigma_rot = declare_parameter<double>("odometry.sigma_rot", on.sigma_rot, D{"rad/√rad", 0.0, 1.0, true});
    on.sigma_rot_per_m = declare_parameter<double>("odometry.sigma_rot_per_m", on.sigma_rot_per_m, D{"rad/√m", 0.0, 1.0, true});

    // Robot (DiffDriveConfig).
    auto& r = cfg.robot;
    r.max_v = declare_parameter<double>("robot.max_v", r.max_v, D{"m/s forward", 0.0, 10.0, true});
    r.max_v_reverse = declare_parameter<double>("robot.max_v_reverse", r.max_v_reverse, D{"m/s backward", 0.0, 10.0, true});
    r.max_w = declare_parameter<double>("robot.max_w", r.max_w, D{"rad/s", 0.0, 20.0, true});
    r.max_acc = declare_parameter<double>("robot.max_acc", r.max_acc, D{"m/s²", 0.01, 100.0, true});
    r.max_dec = declare_parameter<double>("robot.max_dec", r.max_dec, D{"m/s²", 0.01, 100.0, true});
    r.max_alpha = declare_parameter<double>("robot.max_alpha", r.max_alpha, D{"rad/s²", 0.01, 100.0, true});
    r.cmd_timeout = declare_parameter<double>("robot.cmd_timeout", r.cmd_timeout, D{"s (sim time) without cmd_vel -> brake to zero", 0.01, 60.0, true});
    r.stall_on_collision = declare_parameter<bool>("robot.stall_on_collision", r.stall_on_collision, D{"steps into obstacles are not taken", {}, {}, true});
    const std::vector<double> start = declare_parameter<std::vector<double>>(
        "robot.start", {}, D{"[x, y, yaw] overriding the world's robot start; [] = the world's", {}, {}, true});

    // Scripted-route mode (RouteConfig; Stüde §4.3.1).
    const std::string route = declare_parameter<std::string>(
        "route", "", D{"world route to drive using ground truth (scripted mode, cmd_vel ignored); \"\" = cmd_vel mode", {}, {}, true});
    sim::RouteConfig rc;
    rc.speed = declare_parameter<double>("route_speed", rc.speed, D{"m/s cruise speed on the route", 0.01, 5.0, true});
    rc.dwell = declare_parameter<double>("route_dwell", rc.dwell, D{"s stationary stop at every waypoint", 0.0, 3600.0, true});
    rc.loop = declare_parameter<bool>("route_loop", true, D{"start over at the first waypoint", {}, {}, true});

    // People.
    cfg.people = declare_parameter<bool>("people.world", true, D{"the world's recorded and scripted people", {}, {}, true});
    cfg.crowd = declare_parameter<bool>("people.crowd", true, D{"the world's crowd model (Poisson arrivals, periodic rates)", {}, {}, true});
    const std::string people_file = declare_parameter<std::string>(
        "people.file", "", D{"extra recorded trajectories (relative to the working directory); \"\" = none", {}, {}, true});
    const std::string people_format = declare_parameter<std::string>("people.format", "csv", D{"csv (t,id,x,y) | eth_obsmat | edinburgh", {}, {}, true});
    const std::vector<double> people_offset = declare_parameter<std::vector<double>>(
        "people.offset", {0.0, 0.0, 0.0}, D{"[x, y, yaw]: world = offset ⊕ (scale · data)", {}, {}, true});
    const double people_scale = declare_parameter<double>("people.scale", 1.0, D{"scale of the recorded positions", 1e-6, 1e6, true});
    const double people_time_offset = declare_parameter<double>("people.time_offset", 0.0, D{"s added to the recorded times", -1e9, 1e9, true});
    const bool people_loop = declare_parameter<bool>("people.loop", true, D{"replay the recording when it ends", {}, {}, true});

    // World and core. Built in a dry run too: `cairn launch --check` reports an unknown world or route, a bad
    // people file or laser config. Errors name the parameter; the core's InputError adds file:line.
    sim::World world;
    try {
      world = sim::loadWorld(sim::resolveWorldPath(world_param));
    } catch (const std::exception& e) {
      throw std::invalid_argument("world: '" + world_param + "': " + e.what());
    }
    // The core emits at most one scan and one odometry message per physics step: a faster rate would
    // silently give the step rate.
    for (const auto& [name, hz] : {std::pair<const char*, double>{"laser.rate", cfg.laser.rate}, {"odom_rate", cfg.odom_rate}})
      if (hz * cfg.physics_dt > 1.0 + 1e-9) {
        std::ostringstream msg;
        msg << name << ": " << hz << " Hz is more than one message per physics step (physics_dt " << cfg.physics_dt
            << " s: at most " << 1.0 / cfg.physics_dt << " Hz)";
        throw std::invalid_argument(msg.str());
      }
    if (start.size() == 3) {
      cfg.start = sim::Pose2{start[0], start[1], start[2]};
    } else if (!start.empty()) {
      throw std::invalid_argument("robot.start: expected [x, y, yaw], got " + std::to_string(start.size()) + " numbers");
    }
    if (!people_file.empty()) {
      if (people_format != "csv" && people_format != "eth_obsmat" && people_format != "edinburgh")
        throw std::invalid_argument("people.format: must be csv, eth_obsmat or edinburgh, got '" + people_format + "'");
      if (people_offset.size() != 3)
        throw std::invalid_argument("people.offset: expected [x, y, yaw], got " + std::to_string(people_offset.size()) + " numbers");
      sim::PeopleSource src;
      src.kind = people_format;
      src.file = people_file;
      src.offset = sim::Pose2{people_offset[0], people_offset[1], people_offset[2]};
      src.scale = people_scale;
      src.time_offset = people_time_offset;
      src.loop = people_loop;
      world.people.push_back(src);
      cfg.people = true;  // the extra source is one of the "world" sources of the core
    }
    std::vector<sim::Vec2> waypoints;
    if (!route.empty()) {
      const auto it = world.routes.find(route);
      if (it == world.routes.end()) {
        std::string known;
        for (const auto& [name, wp] : world.routes) known += (known.empty() ? "" : ", ") + name;
        throw std::invalid_argument("route: world '" + world.name + "' has no route '" + route + "' (routes: " +
                                    (known.empty() ? "none" : known) + ")");
      }
      waypoints = it->second;
    }
    try {
      sim_ = std::make_unique<sim::Simulator>(std::move(world), cfg);
    } catch (const sim::InputError& e) {
      throw std::invalid_argument(std::string("people.file: ") + e.what());
    }
    // std::invalid_argument from LaserConfig::validate() names the laser field and passes through.
    if (!waypoints.empty()) sim_->followRoute(waypoints, rc);
    route_mode_ = !waypoints.empty();
    nav_config_ = rc;  // navigate_to drives one-waypoint routes at the route speed, without dwell or loop
    nav_config_.dwell = 0.0;
    nav_config_.loop = false;

    group_ = create_callback_group(cairn::CallbackGroup::Type::MutuallyExclusive);
    scan_pub_ = create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS::sensor_data());
    odom_pub_ = create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{});
    gt_pub_ = create_publisher<nav_msgs::msg::Odometry>("ground_truth", cairn::QoS{});
    people_pub_ = create_publisher<cairn_sim_msgs::msg::PersonArray>("people/ground_truth", cairn::QoS{});
    if (publish_tf_ || publish_map_tf_)
      tf_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100));  // tf2 dynamic QoS
    clock_pub_ = create_publisher<rosgraph_msgs::msg::Clock>("/clock", cairn::QoS{}.keep_last(1));
    cmd_sub_ = create_subscription<geometry_msgs::msg::Twist>(
        "cmd_vel", cairn::QoS{}, [this](const geometry_msgs::msg::Twist& m) { onCmdVel(m); }, group_);
    nav_srv_ = create_deferred_service<NavReq, NavResp>(
        "sim/navigate_to", [this](const NavReq& req, std::function<void(NavResp)> reply) { onNavigateTo(req, std::move(reply)); },
        group_);

    CAIRN_INFO(logger(), "world '" << sim_->world().name << "' (" << sim_->world().file << "), seed " << cfg.seed
                                   << ", " << rtf_ << "x real time, " << sim_->config().laser.beams() << " beams at "
                                   << cfg.laser.rate << " Hz, "
                                   << (route_mode_ ? "driving route '" + route + "'" : std::string("cmd_vel mode")));
    if (dry_run()) return;  // no timer in a launch-spec validation
    period_ = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / tick_hz));
    timer_ = create_wall_timer(period_, [this] { tick(); }, group_);
  }

  ~Simulator() override {
    if (timer_) timer_->cancel();
  }

 private:
  using NavReq = cairn_sim_msgs::srv::NavigateTo_Request;
  using NavResp = cairn_sim_msgs::srv::NavigateTo_Response;

  // sim/navigate_to (the NavigateTo stand-in until a navigation component exists): drives a one-waypoint route
  // with the core's RouteFollower on ground truth and replies when the goal ends. One goal at a time: a new goal
  // preempts the old one, `cancel` stops it. Runs in group_, like tick(), so it never races the simulation.
  void onNavigateTo(const NavReq& req, std::function<void(NavResp)> reply) {
    NavResp resp;
    if (req.cancel) {
      const bool had = goal_.has_value();
      endGoal(false, "cancelled");
      if (had) sim_->setCommand({0.0, 0.0});
      resp.success = true;
      resp.message = had ? "cancelled the current goal" : "no goal to cancel";
      fillPose(resp);
      reply(resp);
      return;
    }
    std::optional<sim::Vec2> goal;
    if (route_mode_) {
      resp.message = "driving the scripted route (parameter 'route'); navigate_to needs cmd_vel mode";
    } else if (!req.location.empty()) {
      const auto& world = sim_->world();
      if (const sim::Region* r = world.region(req.location)) {
        goal = r->centroid();
      } else if (auto it = world.routes.find(req.location); it != world.routes.end() && !it->second.empty()) {
        goal = it->second.back();
      } else {
        std::string known;
        for (const auto& r : world.regions) known += (known.empty() ? "" : ", ") + r.name;
        for (const auto& [name, wp] : world.routes) known += (known.empty() ? "" : ", ") + name;
        resp.message = "location: world '" + world.name + "' has no region or route '" + req.location +
                       "' (known: " + (known.empty() ? "none" : known) + ")";
      }
    } else if (!std::isfinite(req.x) || !std::isfinite(req.y)) {
      resp.message = "x, y: goal is not finite";
    } else {
      goal = sim::Vec2{req.x, req.y};
    }
    if (!goal || !std::isfinite(req.timeout_s) || req.timeout_s < 0.0) {
      if (goal) resp.message = "timeout_s: must be >= 0";
      fillPose(resp);
      reply(resp);
      return;
    }
    endGoal(false, "preempted by a new goal");
    sim_->followRoute({*goal}, nav_config_);
    goal_ = Goal{std::move(reply), sim_->time(), req.timeout_s};
  }

  // After every simulation chunk: a goal ends when the follower reached it, or when its time is up.
  void checkGoal() {
    if (!goal_) return;
    if (!sim_->routeActive()) {
      endGoal(true, "arrived");
    } else if (goal_->timeout_s > 0.0 && sim_->time() - goal_->start >= goal_->timeout_s) {
      sim_->cancelRoute();
      sim_->setCommand({0.0, 0.0});
      endGoal(false, "timed out after " + std::to_string(goal_->timeout_s) + " s");
    }
  }

  void endGoal(bool success, const std::string& message) {
    if (!goal_) return;
    if (!success) sim_->cancelRoute();
    NavResp resp;
    resp.success = success;
    resp.message = message;
    resp.elapsed_s = sim_->time() - goal_->start;
    fillPose(resp);
    auto reply = std::move(goal_->reply);
    goal_.reset();
    reply(resp);
  }

  void fillPose(NavResp& resp) const {
    const sim::Pose2 p = sim_->groundTruth();
    resp.x = p.x;
    resp.y = p.y;
    resp.yaw = p.theta;
  }

  void onCmdVel(const geometry_msgs::msg::Twist& m) {
    if (!std::isfinite(m.linear.x) || !std::isfinite(m.angular.z)) {
      CAIRN_WARN(logger(), "cmd_vel: non-finite velocity ignored");
      return;
    }
    if (sim_->routeActive()) {
      if (!warned_route_)
        CAIRN_WARN(logger(), "cmd_vel ignored: driving " << (goal_ ? "a navigate_to goal" : "the scripted route (parameter 'route')"));
      warned_route_ = true;
      return;
    }
    sim_->setCommand({m.linear.x, m.angular.z});
  }

  // Advances the core to rtf × elapsed wall time in chunks that end at the people-publication times, then
  // publishes what each chunk produced and /clock.
  void tick() {
    const auto now = std::chrono::steady_clock::now();
    const double dt = sim_->config().physics_dt;
    if (!started_) {
      started_ = true;
      wall0_ = now;
      sim0_ = sim_->time();
      publishPeople();
      clock_pub_->publish(cv::toClock(sim_->time()));
    }
    double target = sim0_ + rtf_ * std::chrono::duration<double>(now - wall0_).count();
    // Falling behind (slow machine, rtf too high): do at most 0.25 s of wall time's worth per tick, and
    // let the rest go (the real-time factor drops; the simulation itself is unchanged).
    const double cap = std::max(rtf_ * 0.25, dt);
    if (target - sim_->time() > cap) {
      if (!warned_lag_) CAIRN_WARN(logger(), "cannot keep up with real_time_factor " << rtf_ << "; running slower");
      warned_lag_ = true;
      sim0_ -= target - sim_->time() - cap;
      target = sim_->time() + cap;
    }
    for (;;) {
      const long target_steps = static_cast<long>(std::floor((target - sim_->time()) / dt + 1e-6));
      if (target_steps <= 0) break;
      // up to the first step at or after the next people publication time (at least one step)
      const long people_steps = std::max(1L, static_cast<long>(std::ceil((next_people_ - sim_->time()) / dt - 1e-6)));
      const long steps = std::min(target_steps, people_steps);
      out_.scans.clear();
      out_.odometry.clear();
      out_.ground_truth.clear();
      sim_->advance(static_cast<double>(steps) * dt, out_);
      publishOutput();
      checkGoal();
      if (sim_->time() >= next_people_ - 0.5 * dt) publishPeople();
      clock_pub_->publish(cv::toClock(sim_->time()));
    }
  }

  void publishOutput() {
    for (const auto& s : out_.scans) scan_pub_->publish(cv::toMsg(s, s.frame_id));
    for (const auto& o : out_.odometry) odom_pub_->publish(cv::toMsg(o.stamp, o.pose, o.twist, odom_frame_, base_frame_));
    for (const auto& g : out_.ground_truth) gt_pub_->publish(cv::toMsg(g.stamp, g.pose, g.twist, map_frame_, base_frame_));
    if (!tf_pub_ || out_.odometry.empty()) return;
    tf2_msgs::msg::TFMessage tf;
    for (std::size_t i = 0; i < out_.odometry.size(); ++i) {
      const auto& o = out_.odometry[i];
      if (publish_tf_) tf.transforms.push_back(cv::toTransform(o.stamp, o.pose, odom_frame_, base_frame_));
      if (publish_map_tf_ && i < out_.ground_truth.size()) {
        // map -> odom = ground truth ⊕ odometry⁻¹ (the correction a perfect localization would publish)
        const sim::Pose2 map_odom = sim::compose(out_.ground_truth[i].pose, sim::between(o.pose, sim::Pose2{}));
        tf.transforms.push_back(cv::toTransform(o.stamp, map_odom, map_frame_, odom_frame_));
      }
    }
    tf_pub_->publish(std::move(tf));
  }

  void publishPeople() {
    cairn_sim_msgs::msg::PersonArray m;
    m.header.stamp = cv::toTime(sim_->time());
    m.header.frame_id = map_frame_;
    for (const auto& p : sim_->people()) {
      cairn_sim_msgs::msg::PersonState s;
      s.id = p.id;
      s.position.x = p.position.x;
      s.position.y = p.position.y;
      s.velocity.x = p.velocity.x;
      s.velocity.y = p.velocity.y;
      s.heading = p.heading;
      s.left_leg.x = p.legs[0].x;
      s.left_leg.y = p.legs[0].y;
      s.right_leg.x = p.legs[1].x;
      s.right_leg.y = p.legs[1].y;
      s.leg_radius = p.leg_radius;
      m.people.push_back(s);
    }
    people_pub_->publish(std::move(m));
    // Next due time after now (with people.rate above the physics rate: once per step).
    const double half_step = 0.5 * sim_->config().physics_dt;
    do {
      ++people_count_;
      next_people_ = static_cast<double>(people_count_) / people_rate_;
    } while (next_people_ <= sim_->time() + half_step);
  }

  std::unique_ptr<sim::Simulator> sim_;
  sim::SimOutput out_;
  double rtf_ = 1.0, people_rate_ = 10.0;
  std::string map_frame_, odom_frame_, base_frame_;
  bool publish_tf_ = true, publish_map_tf_ = false, route_mode_ = false;
  bool warned_route_ = false, warned_lag_ = false;
  bool started_ = false;
  std::chrono::steady_clock::time_point wall0_;
  double sim0_ = 0.0, next_people_ = 0.0;
  long people_count_ = 0;
  std::chrono::nanoseconds period_{10000000};
  std::shared_ptr<cairn::CallbackGroup> group_;
  std::shared_ptr<cairn::Publisher<sensor_msgs::msg::LaserScan>> scan_pub_;
  std::shared_ptr<cairn::Publisher<nav_msgs::msg::Odometry>> odom_pub_, gt_pub_;
  std::shared_ptr<cairn::Publisher<cairn_sim_msgs::msg::PersonArray>> people_pub_;
  std::shared_ptr<cairn::Publisher<tf2_msgs::msg::TFMessage>> tf_pub_;
  std::shared_ptr<cairn::Publisher<rosgraph_msgs::msg::Clock>> clock_pub_;
  std::shared_ptr<cairn::Subscription<geometry_msgs::msg::Twist>> cmd_sub_;
  std::shared_ptr<cairn::TimerBase> timer_;
  struct Goal {
    std::function<void(NavResp)> reply;
    double start = 0.0;      ///< sim time of the request
    double timeout_s = 0.0;  ///< 0: no limit
  };
  sim::RouteConfig nav_config_;
  std::optional<Goal> goal_;
  std::shared_ptr<cairn::Service<NavReq, NavResp>> nav_srv_;
};

}  // namespace cairn_sim

CAIRN_REGISTER_COMPONENT(cairn_sim::Simulator)
