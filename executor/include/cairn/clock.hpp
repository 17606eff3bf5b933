// Clocks: steady (monotonic), system (wall) and ROS time, which follows /clock when use_sim_time is set.
#ifndef CAIRN_CLOCK_HPP
#define CAIRN_CLOCK_HPP

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <utility>
#include <vector>

namespace cairn {

/// Nanoseconds since the clock's epoch (UNIX epoch for system/ROS time).
struct Time {
  int64_t ns = 0;
  double seconds() const { return static_cast<double>(ns) * 1e-9; }
  static Time from_seconds(double s) { return Time{static_cast<int64_t>(s * 1e9)}; }
  auto operator<=>(const Time&) const = default;
};

enum class ClockType { Steady, System, Ros };

class Clock {
 public:
  explicit Clock(ClockType type = ClockType::Ros) : type_(type) {}
  ClockType type() const { return type_; }
  Time now() const;
  /// Switches a ROS clock to simulated time; now() then returns the last time given to set_sim_time
  /// (0 until the first /clock message).
  void enable_sim_time(bool on);
  bool sim_time_active() const { return sim_.load(); }
  void set_sim_time(Time t);
  /// Called after every sim-time update (executors re-check their timers). Returns an id for
  /// remove_update(); a callback may run on the thread of set_sim_time until remove_update() returns.
  std::uint64_t on_update(std::function<void()> cb);
  void remove_update(std::uint64_t id);
  /// Number of registered update callbacks.
  std::size_t update_callbacks() const;

 private:
  ClockType type_;
  std::atomic<bool> sim_{false};
  std::atomic<int64_t> sim_ns_{0};
  mutable std::mutex cb_mu_;
  std::vector<std::pair<std::uint64_t, std::function<void()>>> callbacks_;
  std::uint64_t next_cb_id_ = 1;
};

}  // namespace cairn

#endif  // CAIRN_CLOCK_HPP
