// cairn_sim::LogPlayer — plays a CARMEN log (cairn/sim/carmen.hpp: FLASER, RLASER, ROBOTLASER1, RAWLASER1-4,
// ODOM; plain, gzip or bzip2) onto the runtime: scan, odom, /tf (odom -> base_link), /tf_static (base_link ->
// laser) and /clock with the log's timestamps, at `rate` × real time or as fast as possible. Streaming: the
// reader keeps one record in memory. The constructor reads the whole log once (also in a launch-spec dry run),
// so a missing, empty or malformed log is a load error naming file:line before anything is published.
#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "cairn/component.hpp"
#include "cairn/sim/carmen.hpp"
#include "convert.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "rosgraph_msgs/msg/Clock.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

namespace cairn_sim {

namespace sim = cairn::sim;
namespace cv = cairn_sim::convert;

class LogPlayer : public cairn::Node {
 public:
  explicit LogPlayer(const cairn::NodeOptions& o) : cairn::Node(o) {
    using D = cairn::ParameterDescriptor;
    file_ = declare_parameter<std::string>("file", "", D{"CARMEN log (.clf, .log, .gz, .bz2); relative to the working directory", {}, {}, true});
    rate_ = declare_parameter<double>("rate", 1.0, D{"playback speed × real time; 0 = as fast as possible", 0.0, 1000.0, true});
    loop_ = declare_parameter<bool>("loop", false, D{"start over at the end (/clock jumps back)", {}, {}, true});
    opts_.skip_malformed = declare_parameter<bool>("skip_malformed", false, D{"skip malformed lines with a warning; false: the log is rejected", {}, {}, true});
    const double tick_hz = declare_parameter<double>("tick_rate", 100.0, D{"Hz, wall timer that publishes the records that fell due", 1.0, 1000.0, true});
    burst_ = static_cast<std::size_t>(declare_parameter<int64_t>("burst", 200, D{"records per tick at rate 0", 1.0, 100000.0, true}));
    start_delay_ = declare_parameter<double>("start_delay", 0.0, D{"s of wall time before the first record (lets subscribers connect)", 0.0, 3600.0, true});
    odom_frame_ = declare_parameter<std::string>("odom_frame", "odom", D{"frame of odom", {}, {}, true});
    base_frame_ = declare_parameter<std::string>("base_frame", "base_link", D{"robot frame", {}, {}, true});
    laser_frame_ = declare_parameter<std::string>("laser_frame", "laser", D{"frame of scan", {}, {}, true});
    publish_tf_ = declare_parameter<bool>("publish_tf", true, D{"odom -> base_link on /tf (ODOM records and the laser records' odometry)", {}, {}, true});
    const bool static_tf = declare_parameter<bool>("publish_laser_tf", true, D{"base_link -> laser on /tf_static from laser.x/y/yaw", {}, {}, true});
    sim::Pose2 mount;
    mount.x = declare_parameter<double>("laser.x", 0.0, D{"m, laser in base_link (CARMEN robot_frontlaser_offset)", -10.0, 10.0, true});
    mount.y = declare_parameter<double>("laser.y", 0.0, D{"m", -10.0, 10.0, true});
    mount.theta = declare_parameter<double>("laser.yaw", 0.0, D{"rad", -3.15, 3.15, true});
    opts_.layout.fov = 3.14159265358979323846 / 180.0 *
                       declare_parameter<double>("laser.fov_deg", 180.0, D{"deg covered by FLASER/RLASER beams (the message has only the count)", 1.0, 360.0, true});
    opts_.layout.max_range = declare_parameter<double>("laser.max_range", opts_.layout.max_range, D{"m, readings at or above are no return (+inf)", 0.1, 1000.0, true});
    if (file_.empty()) throw std::invalid_argument("parameter 'file' is required (a CARMEN log)");

    // One full pass: validates every line (file:line errors) and counts records; constant memory.
    opts_.on_warning = [this](const sim::InputError& e) { CAIRN_WARN(logger(), e.what() << " (skipped)"); };
    std::size_t lasers = 0, odoms = 0;
    double first = 0, last = 0;
    try {
      sim::CarmenReader r(file_, opts_);
      sim::CarmenRecord rec;
      while (r.next(rec)) {
        const double t = sim::stampOf(rec);
        if (lasers + odoms == 0) first = t;
        last = t;
        (std::holds_alternative<sim::CarmenLaser>(rec) ? lasers : odoms)++;
      }
    } catch (const sim::InputError& e) {
      throw std::invalid_argument(std::string("file: ") + e.what());
    }
    if (lasers + odoms == 0) throw std::invalid_argument("file: '" + file_ + "' has no laser or odometry records");

    scan_pub_ = create_publisher<sensor_msgs::msg::LaserScan>("scan", cairn::QoS::sensor_data());
    odom_pub_ = create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{});
    if (publish_tf_) tf_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100));
    if (static_tf) static_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", cairn::QoS::latched());
    clock_pub_ = create_publisher<rosgraph_msgs::msg::Clock>("/clock", cairn::QoS{}.keep_last(1));
    CAIRN_INFO(logger(), file_ << ": " << lasers << " scans, " << odoms << " odometry records, " << (last - first)
                               << " s of log time; playing at " << (rate_ > 0 ? std::to_string(rate_) + "x" : std::string("full speed")));
    if (dry_run()) return;
    if (static_tf) {
      tf2_msgs::msg::TFMessage m;
      m.transforms.push_back(cv::toTransform(0.0, mount, base_frame_, laser_frame_));
      static_pub_->publish(std::move(m));
    }
    open();
    timer_ = create_wall_timer(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / tick_hz)), [this] { tick(); });
  }

  ~LogPlayer() override {
    if (timer_) timer_->cancel();
  }

 private:
  void open() {
    reader_ = std::make_unique<sim::CarmenReader>(file_, opts_);
    pending_.reset();
    started_ = false;
    scans_ = odoms_ = 0;
  }

  // The next record, or nullopt at the end of the log (an error after the constructor's pass, e.g. the
  // file changed on disk, ends playback).
  bool fetch() {
    if (pending_) return true;
    sim::CarmenRecord rec;
    try {
      if (!reader_->next(rec)) return false;
    } catch (const sim::InputError& e) {
      CAIRN_ERROR(logger(), e.what() << "; playback stopped");
      return false;
    }
    pending_ = std::move(rec);
    return true;
  }

  void tick() {
    const auto now = std::chrono::steady_clock::now();
    if (!started_) {
      if (!created_) {
        created_ = true;
        created_at_ = now;
      }
      if (std::chrono::duration<double>(now - created_at_).count() < start_delay_) return;
      if (!fetch()) return finish();
      started_ = true;
      wall0_ = now;
      log0_ = sim::stampOf(*pending_);
    }
    const double target = log0_ + rate_ * std::chrono::duration<double>(now - wall0_).count();
    for (std::size_t n = 0; rate_ > 0 || n < burst_; ++n) {
      if (!fetch()) return finish();
      if (rate_ > 0 && sim::stampOf(*pending_) > target) return;
      publish(*pending_);
      pending_.reset();
    }
  }

  void publish(const sim::CarmenRecord& rec) {
    const double t = sim::stampOf(rec);
    if (t > clock_) {  // /clock never goes back within one pass
      clock_ = t;
      clock_pub_->publish(cv::toClock(t));
    }
    tf2_msgs::msg::TFMessage tf;
    if (const auto* l = std::get_if<sim::CarmenLaser>(&rec)) {
      scan_pub_->publish(cv::toMsg(l->scan, laser_frame_));
      if (l->has_pose) tf.transforms.push_back(cv::toTransform(t, l->robot_pose, odom_frame_, base_frame_));
      ++scans_;
    } else {
      const auto& od = std::get<sim::CarmenOdom>(rec);
      odom_pub_->publish(cv::toMsg(t, od.pose, sim::Twist2{od.tv, od.rv}, odom_frame_, base_frame_));
      tf.transforms.push_back(cv::toTransform(t, od.pose, odom_frame_, base_frame_));
      ++odoms_;
    }
    if (tf_pub_ && !tf.transforms.empty()) tf_pub_->publish(std::move(tf));
  }

  void finish() {
    CAIRN_INFO(logger(), "end of " << file_ << ": played " << scans_ << " scans, " << odoms_ << " odometry records"
                                   << (loop_ ? "; starting over" : ""));
    if (loop_) {
      open();
      clock_ = -1.0;
      return;
    }
    timer_->cancel();
  }

  std::string file_;
  sim::CarmenReaderOptions opts_;
  double rate_ = 1.0, start_delay_ = 0.0;
  bool loop_ = false, publish_tf_ = true;
  std::size_t burst_ = 200;
  std::string odom_frame_, base_frame_, laser_frame_;
  std::unique_ptr<sim::CarmenReader> reader_;
  std::optional<sim::CarmenRecord> pending_;
  bool started_ = false, created_ = false;
  std::chrono::steady_clock::time_point created_at_, wall0_;
  double log0_ = 0.0, clock_ = -1.0;
  std::size_t scans_ = 0, odoms_ = 0;
  std::shared_ptr<cairn::Publisher<sensor_msgs::msg::LaserScan>> scan_pub_;
  std::shared_ptr<cairn::Publisher<nav_msgs::msg::Odometry>> odom_pub_;
  std::shared_ptr<cairn::Publisher<tf2_msgs::msg::TFMessage>> tf_pub_, static_pub_;
  std::shared_ptr<cairn::Publisher<rosgraph_msgs::msg::Clock>> clock_pub_;
  std::shared_ptr<cairn::TimerBase> timer_;
};

}  // namespace cairn_sim

CAIRN_REGISTER_COMPONENT(cairn_sim::LogPlayer)
