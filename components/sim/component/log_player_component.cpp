// cairn_sim::LogPlayer (see log_player.hpp). The constructor opens the log and reads its first `lookahead`
// records (also in a launch-spec dry run), so a missing or empty log or a malformed line among the first records
// is a load error naming file:line before anything is published; a malformed line further on stops playback
// with the same file:line error in the log (or is skipped with `skip_malformed`).
#include "log_player.hpp"

#include <algorithm>
#include <cstdio>
#include <variant>

#include "convert.hpp"

namespace cairn_sim {

namespace sim = cairn::sim;
namespace cv = cairn_sim::convert;
using Clock = std::chrono::steady_clock;

LogPlayer::LogPlayer(const cairn::NodeOptions& o) : cairn::Node(o) {
  using D = cairn::ParameterDescriptor;
  file_ = declare_parameter<std::string>("file", "", D{"CARMEN log (.clf, .log, .gz, .bz2); relative to the working directory", {}, {}, true});
  rate_ = declare_parameter<double>("rate", 1.0, D{"playback speed × real time; 0 = no wall-clock pacing (as fast as possible, or as the consumers allow)", 0.0, 1000.0, true});
  const std::string pace = declare_parameter<std::string>("pace", "time", D{"time: by `rate` only; consumers: also wait until every matched reliable subscriber acknowledged the previous record", {}, {}, true});
  loop_ = declare_parameter<bool>("loop", false, D{"start over at the end (/clock jumps back)", {}, {}, true});
  opts_.reader.skip_malformed = declare_parameter<bool>("skip_malformed", false, D{"skip malformed lines with a warning; false: a malformed line is a load error (first `lookahead` records) or stops playback", {}, {}, true});
  opts_.lookahead = static_cast<std::size_t>(declare_parameter<int64_t>("lookahead", 32, D{"records read ahead (memory bound; validated at load)", 1.0, 100000.0, true}));
  opts_.limit = static_cast<std::size_t>(declare_parameter<int64_t>("limit", 0, D{"records per pass; 0 = the whole log", 0.0, 1e12, true}));
  const double tick_hz = declare_parameter<double>("tick_rate", 100.0, D{"Hz, wall timer that publishes the records that fell due", 1.0, 1000.0, true});
  burst_ = static_cast<std::size_t>(declare_parameter<int64_t>("burst", 200, D{"most records per tick without wall-clock pacing", 1.0, 100000.0, true}));
  start_delay_ = declare_parameter<double>("start_delay", 0.0, D{"s of wall time before the first record (lets subscribers connect)", 0.0, 3600.0, true});
  ack_window_ = static_cast<std::size_t>(declare_parameter<int64_t>("ack_window", 1, D{"pace consumers: records published before waiting for the acknowledgments (1 = each record after the previous one was acknowledged)", 1.0, 100000.0, true}));
  wait_subscribers_ = static_cast<std::size_t>(declare_parameter<int64_t>("wait_for_subscribers", 0, D{"start once scan has this many subscriptions (in and out of process)", 0.0, 1000.0, true}));
  odom_frame_ = declare_parameter<std::string>("odom_frame", "odom", D{"frame of odom", {}, {}, true});
  base_frame_ = declare_parameter<std::string>("base_frame", "base_link", D{"robot frame", {}, {}, true});
  laser_frame_ = declare_parameter<std::string>("laser_frame", "laser", D{"frame of scan", {}, {}, true});
  const bool publish_tf = declare_parameter<bool>("publish_tf", true, D{"odom -> base_link on /tf (ODOM records and the laser records' odometry)", {}, {}, true});
  const bool static_tf = declare_parameter<bool>("publish_laser_tf", true, D{"base_link -> laser on /tf_static from laser.x/y/yaw", {}, {}, true});
  sim::Pose2 mount;
  mount.x = declare_parameter<double>("laser.x", 0.0, D{"m, laser in base_link (CARMEN robot_frontlaser_offset)", -10.0, 10.0, true});
  mount.y = declare_parameter<double>("laser.y", 0.0, D{"m", -10.0, 10.0, true});
  mount.theta = declare_parameter<double>("laser.yaw", 0.0, D{"rad", -3.15, 3.15, true});
  opts_.reader.layout.fov = 3.14159265358979323846 / 180.0 *
                            declare_parameter<double>("laser.fov_deg", 180.0, D{"deg covered by FLASER/RLASER beams (the message has only the count)", 1.0, 360.0, true});
  opts_.reader.layout.max_range = declare_parameter<double>("laser.max_range", opts_.reader.layout.max_range, D{"m, readings at or above are no return (+inf)", 0.1, 1000.0, true});
  if (file_.empty()) throw std::invalid_argument("parameter 'file' is required (a CARMEN log)");
  if (pace != "time" && pace != "consumers") throw std::invalid_argument("pace: '" + pace + "' (expected time or consumers)");
  // (0, 0.001) would wait practically forever for the second record (1e-300: never)
  if (rate_ != 0.0 && rate_ < 0.001) {
    char msg[96];
    std::snprintf(msg, sizeof msg, "rate: %g (expected 0 = no pacing, or 0.001 to 1000)", rate_);
    throw std::invalid_argument(msg);
  }
  consumers_ = pace == "consumers";
  tick_period_ = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / tick_hz));

  opts_.reader.on_warning = [this](const sim::InputError& e) { CAIRN_WARN(logger(), e.what() << " (skipped)"); };
  try {
    playback_ = std::make_unique<sim::LogPlayback>(file_, opts_);
  } catch (const sim::InputError& e) {
    throw std::invalid_argument(std::string("file: ") + e.what());
  }
  max_buffered_ = playback_->maxBuffered();

  // Consumer pacing needs acknowledgments, so scans are reliable then (best effort, like a sensor, otherwise).
  scan_pub_ = create_publisher<sensor_msgs::msg::LaserScan>("scan", consumers_ ? cairn::QoS{} : cairn::QoS::sensor_data());
  odom_pub_ = create_publisher<nav_msgs::msg::Odometry>("odom", cairn::QoS{});
  if (publish_tf) tf_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf", cairn::QoS{}.keep_last(100));
  if (static_tf) static_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", cairn::QoS::latched());
  clock_pub_ = create_publisher<rosgraph_msgs::msg::Clock>("/clock", cairn::QoS{}.keep_last(1));
  CAIRN_INFO(logger(), file_ << ": playing " << (rate_ > 0 ? std::to_string(rate_) + "x real time" : std::string("without wall-clock pacing"))
                             << (consumers_ ? ", paced by the consumers' acknowledgments" : ""));
  if (dry_run()) return;
  if (static_pub_) {
    tf2_msgs::msg::TFMessage m;
    m.transforms.push_back(cv::toTransform(0.0, mount, base_frame_, laser_frame_));
    static_pub_->publish(std::move(m));
  }
  timer_ = create_wall_timer(tick_period_, [this] { tick(); });
}

LogPlayer::~LogPlayer() {
  if (timer_) timer_->cancel();
}

// Start condition: `start_delay` of wall time and `wait_for_subscribers` subscriptions on scan.
bool LogPlayer::started(Clock::time_point now) {
  if (started_) return true;
  if (!created_) {
    created_ = true;
    created_at_ = now;
  }
  if (std::chrono::duration<double>(now - created_at_).count() < start_delay_) return false;
  if (scan_pub_->subscription_count() < wait_subscribers_) return false;
  started_ = true;
  wall0_ = now;
  log0_ = sim::stampOf(*playback_->peek());  // the constructor read at least one record
  return true;
}

// Every publisher's DDS readers acknowledged what was written, waiting until `deadline` at most.
bool LogPlayer::acknowledged(Clock::time_point deadline) {
  const auto left = [&] { return std::max(Clock::duration::zero(), deadline - Clock::now()); };
  if (!scan_pub_->wait_for_all_acked(left()) || !odom_pub_->wait_for_all_acked(left())) return false;
  if (tf_pub_ && !tf_pub_->wait_for_all_acked(left())) return false;
  return clock_pub_->wait_for_all_acked(left());
}

void LogPlayer::tick() {
  if (finished_) return;
  const auto now = Clock::now();
  if (!started(now)) return;
  // The executor thread is lent for at most one tick period; an unacknowledged record is waited for again
  // next tick before anything else is published.
  const auto deadline = now + tick_period_;
  if (awaiting_ack_) {
    if (!acknowledged(deadline)) return;
    awaiting_ack_ = false;
  }
  try {
    for (std::size_t n = 0; rate_ > 0 || n < burst_; ++n) {
      const sim::CarmenRecord* rec = playback_->peek();
      if (!rec) return finish();
      if (rate_ > 0 && sim::stampOf(*rec) > log0_ + rate_ * std::chrono::duration<double>(now - wall0_).count()) return;
      publish(*rec);
      playback_->pop();
      max_buffered_ = playback_->maxBuffered();
      if (consumers_ && ++unacked_ >= ack_window_) {
        unacked_ = 0;
        awaiting_ack_ = true;
        if (!acknowledged(deadline)) return;
        awaiting_ack_ = false;
      }
      if (Clock::now() >= deadline) return;
    }
  } catch (const sim::InputError& e) {
    CAIRN_ERROR(logger(), e.what() << "; playback stopped");
    error_ = e.what();
    failed_ = true;
    finished_ = true;
    timer_->cancel();
  }
}

void LogPlayer::publish(const sim::CarmenRecord& rec) {
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

void LogPlayer::finish() {
  CAIRN_INFO(logger(), "end of " << file_ << ": played " << scans_ << " scans, " << odoms_ << " odometry records"
                                 << (loop_ ? "; starting over" : ""));
  if (loop_) {
    playback_->rewind();
    clock_ = -1.0;
    wall0_ = Clock::now();
    if (const sim::CarmenRecord* first = playback_->peek()) log0_ = sim::stampOf(*first);
    return;
  }
  finished_ = true;
  timer_->cancel();
}

}  // namespace cairn_sim

CAIRN_REGISTER_COMPONENT(cairn_sim::LogPlayer)
