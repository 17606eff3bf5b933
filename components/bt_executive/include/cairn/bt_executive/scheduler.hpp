// The interface between the tree and whatever drives it. Async nodes never own threads: they ask the scheduler
// for a wake-up at a time point (timers) or, when an event arrives on some executor thread (message, service
// reply), call requestTick(). The runtime adapter implements Scheduler on top of its executor; tests and the CLI
// use ManualScheduler / a step clock.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

namespace cairn::bt {

using Duration = std::chrono::nanoseconds;
/// Time since an arbitrary epoch of the scheduler's clock (steady, sim or manual time).
using TimePoint = std::chrono::nanoseconds;

class Scheduler {
 public:
  using TimerId = std::uint64_t;
  virtual ~Scheduler() = default;
  /// Current time of the tree's clock.
  virtual TimePoint now() const = 0;
  /// Asks for a tick of the tree at or after `t`. Returns an id for cancelTimer().
  virtual TimerId wakeUpAt(TimePoint t) = 0;
  virtual void cancelTimer(TimerId id) = 0;
  /// Asks for a tick as soon as possible. Thread-safe: async actions call it from executor threads.
  virtual void requestTick() = 0;
};

/// Deterministic scheduler for tests and offline runs: time only moves when the driver advances it.
class ManualScheduler final : public Scheduler {
 public:
  explicit ManualScheduler(TimePoint start = TimePoint{0}) : now_(start.count()) {}
  TimePoint now() const override { return TimePoint{now_.load()}; }
  TimerId wakeUpAt(TimePoint t) override;
  void cancelTimer(TimerId id) override;
  void requestTick() override { tick_requested_.store(true); }

  void advanceTo(TimePoint t) { now_.store(t.count()); }
  void advanceBy(Duration d) { now_.fetch_add(d.count()); }
  /// Earliest pending timer (not yet due or due).
  std::optional<TimePoint> nextTimer() const;
  /// Removes timers due at now(); returns how many fired.
  std::size_t fireDueTimers();
  /// True (and clears the flag) if requestTick() was called since the last call.
  bool takeTickRequest() { return tick_requested_.exchange(false); }
  std::size_t pendingTimers() const;

 private:
  struct Timer {
    TimePoint t;
    TimerId id;
  };
  std::atomic<std::int64_t> now_;
  std::atomic<bool> tick_requested_{false};
  mutable std::mutex mutex_;
  std::vector<Timer> timers_;
  TimerId next_id_ = 1;
};

/// Scheduler on std::chrono::steady_clock that only records requests (for simple loops that tick periodically).
class SteadyScheduler final : public Scheduler {
 public:
  TimePoint now() const override;
  TimerId wakeUpAt(TimePoint) override { return next_id_++; }
  void cancelTimer(TimerId) override {}
  void requestTick() override { tick_requested_.store(true); }
  bool takeTickRequest() { return tick_requested_.exchange(false); }

 private:
  std::atomic<bool> tick_requested_{false};
  TimerId next_id_ = 1;
};

}  // namespace cairn::bt
