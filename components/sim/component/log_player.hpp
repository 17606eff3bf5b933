// cairn_sim::LogPlayer — plays a CARMEN log (cairn/sim/carmen.hpp: FLASER, RLASER, ROBOTLASER1, RAWLASER1-4,
// ODOM; plain, gzip or bzip2) onto the runtime: scan, odom, /tf (odom -> base_link), /tf_static (base_link ->
// laser) and /clock with the log's timestamps, at `rate` × real time, as fast as possible, or as fast as the
// consumers acknowledge (`pace: consumers`). Streaming (cairn::sim::LogPlayback): at most `lookahead` records
// in memory. Declared in a header so that in-process hosts (`cairn log play`, tests) that loaded it through a
// ComponentManager can watch its progress; only inline members are used from outside the component library.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <memory>
#include <string>

#include "cairn/component.hpp"
#include "cairn/sim/log_playback.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "rosgraph_msgs/msg/Clock.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

namespace cairn_sim {

class LogPlayer : public cairn::Node {
 public:
  explicit LogPlayer(const cairn::NodeOptions& o);
  ~LogPlayer() override;

  /// True once the last pass ended (end of log, `limit`, or an error that stopped playback); never with `loop`.
  bool finished() const { return finished_.load(); }
  /// True if playback stopped on a malformed line (the error was logged with file:line).
  bool failed() const { return failed_.load(); }
  /// The error that stopped playback ("file:line: what"); valid once finished() is true.
  const std::string& error() const { return error_; }
  std::size_t scansPublished() const { return scans_.load(); }
  std::size_t odometryPublished() const { return odoms_.load(); }
  /// Most records the player held in memory at once (bounded by `lookahead`, whatever the log's length).
  std::size_t maxBufferedRecords() const { return max_buffered_.load(); }

 private:
  void tick();
  bool started(std::chrono::steady_clock::time_point now);
  bool acknowledged(std::chrono::steady_clock::time_point deadline);
  void publish(const cairn::sim::CarmenRecord& rec);
  void finish();

  std::string file_;
  cairn::sim::LogPlaybackOptions opts_;
  std::unique_ptr<cairn::sim::LogPlayback> playback_;
  double rate_ = 1.0, start_delay_ = 0.0;
  bool loop_ = false, consumers_ = false;
  std::size_t burst_ = 200, wait_subscribers_ = 0, ack_window_ = 1, unacked_ = 0;
  std::chrono::nanoseconds tick_period_{10000000};
  std::string odom_frame_, base_frame_, laser_frame_;
  bool started_ = false, created_ = false, awaiting_ack_ = false;
  std::chrono::steady_clock::time_point created_at_, wall0_;
  double log0_ = 0.0, clock_ = -1.0;
  std::string error_;
  std::atomic<bool> finished_{false}, failed_{false};
  std::atomic<std::size_t> scans_{0}, odoms_{0}, max_buffered_{0};
  std::shared_ptr<cairn::Publisher<sensor_msgs::msg::LaserScan>> scan_pub_;
  std::shared_ptr<cairn::Publisher<nav_msgs::msg::Odometry>> odom_pub_;
  std::shared_ptr<cairn::Publisher<tf2_msgs::msg::TFMessage>> tf_pub_, static_pub_;
  std::shared_ptr<cairn::Publisher<rosgraph_msgs::msg::Clock>> clock_pub_;
  std::shared_ptr<cairn::TimerBase> timer_;
};

}  // namespace cairn_sim
