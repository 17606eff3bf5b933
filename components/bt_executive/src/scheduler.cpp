#include "cairn/bt_executive/scheduler.hpp"

#include <algorithm>

namespace cairn::bt {

Scheduler::TimerId ManualScheduler::wakeUpAt(TimePoint t) {
  std::lock_guard lock(mutex_);
  TimerId id = next_id_++;
  timers_.push_back({t, id});
  return id;
}

void ManualScheduler::cancelTimer(TimerId id) {
  std::lock_guard lock(mutex_);
  std::erase_if(timers_, [id](const Timer& t) { return t.id == id; });
}

std::optional<TimePoint> ManualScheduler::nextTimer() const {
  std::lock_guard lock(mutex_);
  if (timers_.empty()) return std::nullopt;
  auto it = std::min_element(timers_.begin(), timers_.end(), [](auto& a, auto& b) { return a.t < b.t; });
  return it->t;
}

std::size_t ManualScheduler::fireDueTimers() {
  std::lock_guard lock(mutex_);
  const TimePoint n = TimePoint{now_.load()};
  return std::erase_if(timers_, [n](const Timer& t) { return t.t <= n; });
}

std::size_t ManualScheduler::pendingTimers() const {
  std::lock_guard lock(mutex_);
  return timers_.size();
}

TimePoint SteadyScheduler::now() const {
  return std::chrono::duration_cast<TimePoint>(std::chrono::steady_clock::now().time_since_epoch());
}

}  // namespace cairn::bt
