#include "cairn/clock.hpp"

namespace cairn {

Time Clock::now() const {
  if (type_ == ClockType::Steady) {
    return Time{std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::steady_clock::now().time_since_epoch()).count()};
  }
  if (type_ == ClockType::Ros && sim_.load(std::memory_order_acquire)) {
    return Time{sim_ns_.load(std::memory_order_acquire)};
  }
  return Time{std::chrono::duration_cast<std::chrono::nanoseconds>(
                  std::chrono::system_clock::now().time_since_epoch()).count()};
}

void Clock::enable_sim_time(bool on) { sim_.store(on); }

void Clock::set_sim_time(Time t) {
  sim_ns_.store(t.ns, std::memory_order_release);
  std::vector<std::pair<std::uint64_t, std::function<void()>>> cbs;
  {
    std::lock_guard l(cb_mu_);
    cbs = callbacks_;
  }
  for (auto& [id, cb] : cbs) cb();
}

std::uint64_t Clock::on_update(std::function<void()> cb) {
  std::lock_guard l(cb_mu_);
  callbacks_.emplace_back(next_cb_id_, std::move(cb));
  return next_cb_id_++;
}

void Clock::remove_update(std::uint64_t id) {
  std::lock_guard l(cb_mu_);
  std::erase_if(callbacks_, [id](const auto& c) { return c.first == id; });
}

std::size_t Clock::update_callbacks() const {
  std::lock_guard l(cb_mu_);
  return callbacks_.size();
}

}  // namespace cairn
