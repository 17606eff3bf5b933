// cairn_graph_slam::SlamNode — the runtime adapter of the 2D graph SLAM (slam.hpp): LaserScan + Odometry + TF in;
// map (OccupancyGrid, transient local), map -> odom TF, pose with covariance and the pose graph out; services to
// save / load the state and to optimize now. Thin: message conversion, parameters (the slam_params.hpp table, so
// names, ranges and docs are the `cairn slam run --config` keys) and calls into the core. Bad input (malformed
// scans, time going backwards, missing odometry, a bad state file) is logged and skipped; the node keeps running.
#include <chrono>
#include <cmath>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "cairn/component.hpp"
#include "cairn/graph_slam/slam.hpp"
#include "cairn/graph_slam/slam_params.hpp"
#include "cairn/msg_conversions.hpp"
#include "cairn/tf.hpp"
#include "cairn_slam_msgs/msg/SlamGraph.hpp"
#include "cairn_slam_msgs/srv/LoadState.hpp"
#include "cairn_slam_msgs/srv/Optimize.hpp"
#include "cairn_slam_msgs/srv/SaveState.hpp"
#include "geometry_msgs/msg/PoseWithCovarianceStamped.hpp"
#include "nav_msgs/msg/OccupancyGrid.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

namespace cairn_graph_slam {

namespace gs = cairn::graph_slam;
namespace smsg = cairn_slam_msgs::msg;
namespace ssrv = cairn_slam_msgs::srv;

namespace {

using cairn::quaternion_from_yaw;
using cairn::time_from_seconds;
using cairn::to_seconds;
using cairn::yaw_of;

cairn::sim::LaserScan toCore(const sensor_msgs::msg::LaserScan& m) {
  cairn::sim::LaserScan s;
  s.stamp = to_seconds(m.header.stamp);
  s.frame_id = m.header.frame_id;
  s.angle_min = m.angle_min;
  s.angle_max = m.angle_max;
  s.angle_increment = m.angle_increment;
  s.time_increment = m.time_increment;
  s.scan_time = m.scan_time;
  s.range_min = m.range_min;
  s.range_max = m.range_max;
  s.ranges = m.ranges;
  s.intensities = m.intensities;
  return s;
}

}  // namespace

class SlamNode : public cairn::Node {
 public:
  explicit SlamNode(const cairn::NodeOptions& o) : cairn::Node(o) {
    using D = cairn::ParameterDescriptor;
    // Every SLAM parameter of the core's table, typed, with its range and description.
    for (const gs::SlamParam& p : gs::slamParameters()) {
      D d{p.description, {}, {}, true};
      if (p.min > -1e299) d.min = p.min;
      if (p.max < 1e299) d.max = p.max;
      const gs::SlamParamRef ref = p.ref(options_);
      if (auto* v = std::get_if<double*>(&ref)) {
        **v = declare_parameter<double>(p.name, **v, d);
      } else if (auto* i = std::get_if<int*>(&ref)) {
        **i = static_cast<int>(declare_parameter<int64_t>(p.name, **i, d));
      } else if (auto* b = std::get_if<bool*>(&ref)) {
        **b = declare_parameter<bool>(p.name, **b, d);
      } else {
        *std::get<std::string*>(ref) = declare_parameter<std::string>(p.name, *std::get<std::string*>(ref), d);
      }
    }
    base_frame_ = declare_parameter<std::string>("base_frame", "base_link", D{"robot base frame", {}, {}, true});
    odom_frame_ = declare_parameter<std::string>("odom_frame", "odom", D{"odometry frame (= the local SLAM frame)", {}, {}, true});
    map_frame_ = declare_parameter<std::string>("map_frame", "map", D{"map frame", {}, {}, true});
    use_odom_ = declare_parameter<bool>("use_odom", true, D{"use `odom` as the motion prior (false: constant velocity)", {}, {}, true});
    odom_tolerance_ = declare_parameter<double>("odom_tolerance", 0.2, D{"s, largest scan-odometry stamp difference", 0.0, 5.0, true});
    tf_timeout_ = declare_parameter<double>("tf_timeout", 2.0, D{"s of scans to wait for base->laser TF before using laser_x/y/theta", 0.0, 60.0, true});
    map_period_ = declare_parameter<double>("map_publish_period", 5.0, D{"s, least time between map rebuilds (a rebuild follows new nodes or an optimization)", 0.1, 3600.0, true});
    const std::string load = declare_parameter<std::string>("load_state", "", D{"state file to start from (empty: new map)", {}, {}, true});

    if (!load.empty()) {
      slam_ = std::make_unique<gs::GraphSlam>(gs::GraphSlam::load(load, options_));
      CAIRN_INFO(logger(), "loaded " << load << " (" << slam_->nodes().size() << " nodes)");
    } else {
      slam_ = std::make_unique<gs::GraphSlam>(options_);
    }
    tf_buffer_ = std::make_shared<cairn::TransformBuffer>(30.0);
    tf_listener_ = std::make_unique<cairn::TransformListener>(*this, tf_buffer_);

    map_pub_ = create_publisher<nav_msgs::msg::OccupancyGrid>("map", cairn::QoS::latched());
    pose_pub_ = create_publisher<geometry_msgs::msg::PoseWithCovarianceStamped>("slam/pose", cairn::QoS{});
    graph_pub_ = create_publisher<smsg::SlamGraph>("slam/graph", cairn::QoS{});
    tf_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100));
    scan_sub_ = create_subscription<sensor_msgs::msg::LaserScan>(
        "scan", cairn::QoS::sensor_data(), [this](const sensor_msgs::msg::LaserScan& m) { onScan(m); });
    if (use_odom_)
      odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
          "odom", cairn::QoS{}, [this](const nav_msgs::msg::Odometry& m) { onOdom(m); });
    save_srv_ = create_service<ssrv::SaveState_Request, ssrv::SaveState_Response>(
        "slam/save_state", [this](const ssrv::SaveState_Request& rq, ssrv::SaveState_Response& rs) { onSave(rq, rs); });
    load_srv_ = create_service<ssrv::LoadState_Request, ssrv::LoadState_Response>(
        "slam/load_state", [this](const ssrv::LoadState_Request& rq, ssrv::LoadState_Response& rs) { onLoad(rq, rs); });
    opt_srv_ = create_service<ssrv::Optimize_Request, ssrv::Optimize_Response>(
        "slam/optimize", [this](const ssrv::Optimize_Request& rq, ssrv::Optimize_Response& rs) { onOptimize(rq, rs); });
    CAIRN_INFO(logger(), "graph SLAM: " << (options_.localization_only ? "localization on the loaded map" : "mapping")
                                        << ", verifier " << (options_.use_verifier ? "on" : "off"));
  }

 private:
  void onOdom(const nav_msgs::msg::Odometry& m) {
    const double t = to_seconds(m.header.stamp);
    const gs::Pose2 p{{m.pose.pose.position.x, m.pose.pose.position.y}, yaw_of(m.pose.pose.orientation)};
    if (!std::isfinite(t) || !p.t.allFinite() || !std::isfinite(p.theta)) return;
    if (!odom_.empty() && t < odom_.back().stamp) odom_.clear();  // time jumped back (log restarted)
    odom_.push_back(gs::StampedPose2{t, p});
    while (odom_.size() > 400) odom_.pop_front();
  }

  // Laser mount from TF (base_frame <- scan frame); after tf_timeout seconds of scans without it, the
  // laser_x/y/theta parameters.
  bool resolveMount(const sensor_msgs::msg::LaserScan& m, double stamp) {
    if (mount_known_) return true;
    if (!first_scan_stamp_) first_scan_stamp_ = stamp;
    try {
      const cairn::RigidTransform tf = tf_buffer_->lookup(base_frame_, m.header.frame_id, cairn::Time{0});
      const Eigen::Vector3d x = tf.q * Eigen::Vector3d::UnitX();
      options_.sensor_in_base = gs::Pose2{{tf.t.x(), tf.t.y()}, std::atan2(x.y(), x.x())};
      CAIRN_INFO(logger(), "laser mount from TF " << base_frame_ << " <- " << m.header.frame_id << ": ("
                                                  << tf.t.x() << ", " << tf.t.y() << ", " << options_.sensor_in_base.theta << ")");
    } catch (const cairn::TransformError& e) {
      if (stamp - *first_scan_stamp_ < tf_timeout_) return false;
      CAIRN_WARN(logger(), "no TF " << base_frame_ << " <- " << m.header.frame_id << " after " << tf_timeout_
                                    << " s (" << e.what() << "): using laser_x/laser_y/laser_theta");
    }
    mount_known_ = true;
    slam_->setSensorInBase(options_.sensor_in_base);
    return true;
  }

  void onScan(const sensor_msgs::msg::LaserScan& m) {
    const double stamp = to_seconds(m.header.stamp);
    if (!resolveMount(m, stamp)) return;
    std::optional<gs::Pose2> odom;
    if (use_odom_) {
      odom = gs::poseAt(odom_, stamp, odom_tolerance_);
      if (!odom) warnOnce("no odometry within " + std::to_string(odom_tolerance_) + " s of the scan; predicting");
    }
    const std::optional<gs::ScanUpdate> u = slam_->addScan(toCore(m), odom);
    if (!u) {
      warnOnce("scan skipped: " + slam_->lastError());
      return;
    }
    publishPose(m.header.stamp, *u);
    publishTf(m.header.stamp, u->pose, odom);
    // The map is rebuilt from every node's scan (GraphSlam::map(), O(nodes)), so it is rebuilt at most once per
    // map_publish_period even when optimizations come faster: on a patrol over mapped ground the graph is
    // re-optimized about once a second and a rebuild after each one grew to most of this thread's time (the
    // demo's endurance run, docs/benchmarks.md). A change (new node, optimization) waits for the next due scan.
    map_dirty_ = map_dirty_ || u->node_added || u->optimized;
    const bool map_due = stamp - last_map_stamp_ >= map_period_ || stamp < last_map_stamp_;
    if (map_dirty_ && map_due) {
      publishMap(m.header.stamp);
      publishGraph(m.header.stamp);
      last_map_stamp_ = stamp;
      map_dirty_ = false;
    }
  }

  void warnOnce(const std::string& what) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_warning_ < std::chrono::seconds(1)) return;
    last_warning_ = now;
    CAIRN_WARN(logger(), what);
  }

  void publishPose(const builtin_interfaces::msg::Time& stamp, const gs::ScanUpdate& u) {
    geometry_msgs::msg::PoseWithCovarianceStamped p;
    p.header.stamp = stamp;
    p.header.frame_id = map_frame_;
    p.pose.pose.position.x = u.pose.t.x();
    p.pose.pose.position.y = u.pose.t.y();
    p.pose.pose.orientation = quaternion_from_yaw(u.pose.theta);
    // 6x6 row-major (x, y, z, roll, pitch, yaw): the accumulated uncertainty since the last loop closure.
    const int idx[3] = {0, 1, 5};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) p.pose.covariance[static_cast<std::size_t>(idx[r] * 6 + idx[c])] = u.covariance(r, c);
    pose_pub_->publish(std::move(p));
  }

  // map -> odom (REP 105): the one that takes the scan's odometry pose to its map pose, map_pose * odom_pose^-1.
  // The SLAM's local frame (GraphSlam::mapToLocal) is the odometry frame only if the first scan had odometry, and
  // only as far as scan matching has not corrected the odometry since. The simulator's first scans come before its
  // first odometry: the local frame then started at the origin while the odometry frame had the robot at its start
  // pose, and consumers putting the map into the odometry frame (the people tracker's static map) were off by it.
  // A scan without odometry repeats the last map -> odom; before any, and without odometry at all (use_odom
  // false), the local frame stands for the odometry frame.
  void publishTf(const builtin_interfaces::msg::Time& stamp, const gs::Pose2& map_pose, const std::optional<gs::Pose2>& odom) {
    if (odom) map_to_odom_ = gs::compose(map_pose, gs::inverse(*odom));
    const gs::Pose2 m2o = map_to_odom_ ? *map_to_odom_ : slam_->mapToLocal();
    tf2_msgs::msg::TFMessage tf;
    geometry_msgs::msg::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = map_frame_;
    t.child_frame_id = odom_frame_;
    t.transform.translation.x = m2o.t.x();
    t.transform.translation.y = m2o.t.y();
    t.transform.rotation = quaternion_from_yaw(m2o.theta);
    tf.transforms.push_back(t);
    tf_pub_->publish(std::move(tf));
  }

  void publishMap(const builtin_interfaces::msg::Time& stamp) {
    const gs::OccupancyGrid g = slam_->map();
    nav_msgs::msg::OccupancyGrid msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = map_frame_;
    msg.info.map_load_time = stamp;
    msg.info.resolution = static_cast<float>(g.resolution);
    msg.info.width = static_cast<uint32_t>(g.width);
    msg.info.height = static_cast<uint32_t>(g.height);
    msg.info.origin.position.x = g.origin.x();
    msg.info.origin.position.y = g.origin.y();
    msg.info.origin.orientation.w = 1.0;
    msg.data = g.data;
    map_pub_->publish(std::move(msg));
  }

  void publishGraph(const builtin_interfaces::msg::Time& stamp) {
    smsg::SlamGraph g;
    g.header.stamp = stamp;
    g.header.frame_id = map_frame_;
    for (const gs::SlamNode& n : slam_->nodes()) {
      geometry_msgs::msg::Pose2D p;
      p.x = n.global_pose.t.x();
      p.y = n.global_pose.t.y();
      p.theta = n.global_pose.theta;
      g.nodes.push_back(p);
    }
    for (const gs::SlamEdge& e : slam_->edges()) {
      g.edge_from.push_back(static_cast<uint32_t>(e.from));
      g.edge_to.push_back(static_cast<uint32_t>(e.to));
      g.edge_kind.push_back(static_cast<uint8_t>(e.kind));
    }
    g.loops_accepted = static_cast<uint32_t>(slam_->stats().loops_accepted);
    g.localized = slam_->localized();
    graph_pub_->publish(std::move(g));
  }

  void onSave(const ssrv::SaveState_Request& rq, ssrv::SaveState_Response& rs) {
    try {
      if (rq.path.empty()) throw std::invalid_argument("path is empty");
      slam_->save(rq.path);
      if (!rq.map_stem.empty()) gs::writeMapServer(slam_->map(), rq.map_stem);
      rs.success = true;
      rs.nodes = static_cast<uint32_t>(slam_->nodes().size());
      rs.message = "saved " + std::to_string(rs.nodes) + " nodes to " + rq.path;
    } catch (const std::exception& e) {
      rs.success = false;
      rs.message = e.what();
      CAIRN_ERROR(logger(), "save_state: " << e.what());
    }
  }

  void onLoad(const ssrv::LoadState_Request& rq, ssrv::LoadState_Response& rs) {
    try {
      gs::SlamOptions o = options_;
      o.localization_only = rq.localization_only;
      auto loaded = std::make_unique<gs::GraphSlam>(gs::GraphSlam::load(rq.path, o));
      slam_ = std::move(loaded);  // only replaced once the file loaded completely: nothing is lost on error
      options_ = o;
      rs.success = true;
      rs.nodes = static_cast<uint32_t>(slam_->nodes().size());
      rs.message = "loaded " + std::to_string(rs.nodes) + " nodes from " + rq.path;
      last_map_stamp_ = -1e18;
      map_dirty_ = true;  // the loaded map goes out with the next scan (also in localization-only mode)
      map_to_odom_.reset();  // another map frame: from the next scan with odometry
    } catch (const std::exception& e) {
      rs.success = false;
      rs.message = e.what();
      CAIRN_ERROR(logger(), "load_state: " << e.what());
    }
  }

  void onOptimize(const ssrv::Optimize_Request& rq, ssrv::Optimize_Response& rs) {
    const gs::OptimizerSummary s = slam_->optimize();
    rs.success = true;
    rs.iterations = static_cast<uint32_t>(s.iterations);
    rs.initial_chi2 = s.initial_chi2;
    rs.final_chi2 = s.final_chi2;
    rs.time_s = s.time_s;
    rs.message = s.termination;
    if (rq.republish_map) {
      const builtin_interfaces::msg::Time stamp = time_from_seconds(slam_->trajectory().empty() ? 0.0 : slam_->trajectory().back().stamp);
      publishMap(stamp);
      publishGraph(stamp);
    }
  }

  gs::SlamOptions options_;
  std::unique_ptr<gs::GraphSlam> slam_;
  std::string base_frame_, odom_frame_, map_frame_;
  bool use_odom_ = true;
  double odom_tolerance_ = 0.2, tf_timeout_ = 2.0, map_period_ = 5.0;
  std::deque<gs::StampedPose2> odom_;
  bool mount_known_ = false;
  std::optional<double> first_scan_stamp_;
  std::optional<gs::Pose2> map_to_odom_;  ///< from the last scan with odometry (publishTf)
  double last_map_stamp_ = -1e18;
  bool map_dirty_ = true;  ///< nodes added or poses optimized since the last map (true: a loaded map goes out)
  std::chrono::steady_clock::time_point last_warning_{};
  std::shared_ptr<cairn::TransformBuffer> tf_buffer_;
  std::unique_ptr<cairn::TransformListener> tf_listener_;
  std::shared_ptr<cairn::Publisher<nav_msgs::msg::OccupancyGrid>> map_pub_;
  std::shared_ptr<cairn::Publisher<geometry_msgs::msg::PoseWithCovarianceStamped>> pose_pub_;
  std::shared_ptr<cairn::Publisher<smsg::SlamGraph>> graph_pub_;
  std::shared_ptr<cairn::Publisher<tf2_msgs::msg::TFMessage>> tf_pub_;
  std::shared_ptr<cairn::Subscription<sensor_msgs::msg::LaserScan>> scan_sub_;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<cairn::Service<ssrv::SaveState_Request, ssrv::SaveState_Response>> save_srv_;
  std::shared_ptr<cairn::Service<ssrv::LoadState_Request, ssrv::LoadState_Response>> load_srv_;
  std::shared_ptr<cairn::Service<ssrv::Optimize_Request, ssrv::Optimize_Response>> opt_srv_;
};

}  // namespace cairn_graph_slam

CAIRN_REGISTER_COMPONENT(cairn_graph_slam::SlamNode)
