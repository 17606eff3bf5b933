#include "cairn/executor.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <set>

namespace cairn {

namespace {
thread_local const Executor* tl_executor = nullptr;
thread_local const CallbackGroup* tl_group = nullptr;
thread_local int tl_inline_depth = 0;
constexpr int kMaxInlineDepth = 16;  // deeper same-thread chains go through the queue (no stack blow-up)

std::mutex& all_mu() {
  static std::mutex m;
  return m;
}
std::set<Executor*>& all_executors() {
  static std::set<Executor*> s;
  return s;
}
std::atomic<bool> g_signal{false};
int g_signal_pipe[2] = {-1, -1};
}  // namespace

// ---------------- Executable ----------------
void Executable::disable() {
  enabled_.store(false, std::memory_order_release);
  std::lock_guard l(run_mu_);  // waits for a callback in flight on another thread
}

// ---------------- TimerBase ----------------
TimerBase::TimerBase(std::shared_ptr<CallbackGroup> g, std::shared_ptr<Clock> clock, std::chrono::nanoseconds period,
                     std::function<void()> cb)
    : Executable(std::move(g)), clock_(std::move(clock)), period_(period), cb_(std::move(cb)) {
  next_due_ = clock_->now().ns + period_.count();
}

void TimerBase::reset() {
  next_due_ = clock_->now().ns + period_.count();
  canceled_ = false;
}

void TimerBase::execute() {
  if (canceled_) return;
  const int64_t now = clock_->now().ns;
  int64_t next = next_due_.load() + period_.count();
  if (next <= now) next = now + period_.count();  // missed periods are skipped, not replayed
  next_due_ = next;
  if (one_shot_) canceled_ = true;
  cb_();
}

// ---------------- Executor ----------------
Executor::Executor() : Executor(Options{}) {}

// Lets a clock's update callback reach the executor only while it exists: ~Executor clears `executor` under
// `mu`, so an update running on another thread either finishes first or sees nullptr.
struct Executor::ClockHook {
  std::mutex mu;
  Executor* executor = nullptr;
};

Executor::Executor(Options opts) : opts_(opts), clock_hook_(std::make_shared<ClockHook>()) {
  clock_hook_->executor = this;
  if (opts_.threads == 0) opts_.threads = std::max(1u, std::thread::hardware_concurrency());
  ring_.resize(64);
  std::lock_guard l(all_mu());
  all_executors().insert(this);
}

Executor::~Executor() {
  {
    std::lock_guard l(all_mu());
    all_executors().erase(this);
  }
  {
    std::lock_guard l(clock_hook_->mu);
    clock_hook_->executor = nullptr;
  }
  for (auto& [clock, id] : hooked_clocks_) clock->remove_update(id);
  cancel();
}

void Executor::push_locked(std::shared_ptr<Executable> e) {
  if (size_ == ring_.size()) {
    std::vector<std::shared_ptr<Executable>> bigger(ring_.size() * 2);
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = std::move(ring_[(head_ + i) % ring_.size()]);
    ring_ = std::move(bigger);
    head_ = 0;
  }
  ring_[(head_ + size_) % ring_.size()] = std::move(e);
  ++size_;
  ready_count_.store(size_, std::memory_order_release);
}

std::shared_ptr<Executable> Executor::pop_locked() {
  if (size_ == 0) return nullptr;
  auto e = std::move(ring_[head_]);
  head_ = (head_ + 1) % ring_.size();
  --size_;
  ready_count_.store(size_, std::memory_order_release);
  return e;
}

void Executor::schedule(const std::shared_ptr<Executable>& e) {
  bool wake;
  {
    std::lock_guard l(mu_);
    push_locked(e);
    wake = sleeping_ > 0;
  }
  // Notified after unlocking: a thread woken while this one still holds mu_ would find it taken and sleep once
  // more on the mutex (`cairn bench ipc --only dispatch`: 1.5 instead of 1 wake-up per message). A sleeper
  // counted above is inside cv_.wait, which released mu_ atomically, so the notification cannot be lost.
  if (wake) cv_.notify_one();
}

void Executor::add_timer(const std::shared_ptr<TimerBase>& t) {
  {
    std::lock_guard l(mu_);
    timers_.push_back(t);
    const std::shared_ptr<Clock>& c = t->clock();
    const bool hooked = std::any_of(hooked_clocks_.begin(), hooked_clocks_.end(),
                                    [&](const auto& h) { return h.first == c; });
    if (c->type() == ClockType::Ros && !hooked) {
      // sim time moves in jumps: re-check timers whenever it does
      const std::uint64_t id = c->on_update([h = clock_hook_] {
        std::lock_guard l(h->mu);
        if (h->executor != nullptr) h->executor->notify();
      });
      hooked_clocks_.emplace_back(c, id);
    }
  }
  notify();
}

std::size_t Executor::timer_count() const {
  std::lock_guard l(mu_);
  return timers_.size();
}

void Executor::remove_timer(const TimerBase* t) {
  std::lock_guard l(mu_);
  timers_.erase(std::remove_if(timers_.begin(), timers_.end(), [t](const auto& p) { return p.get() == t; }),
                timers_.end());
}

namespace {
class PostedWork : public Executable {
 public:
  PostedWork(std::shared_ptr<CallbackGroup> g, std::function<void()> fn) : Executable(std::move(g)), fn_(std::move(fn)) {}

 protected:
  void execute() override { fn_(); }

 private:
  std::function<void()> fn_;
};
}  // namespace

void Executor::post(std::function<void()> fn, std::shared_ptr<CallbackGroup> group) {
  if (!group) group = std::make_shared<CallbackGroup>(CallbackGroup::Type::MutuallyExclusive);
  schedule(std::make_shared<PostedWork>(std::move(group), std::move(fn)));
}

void Executor::notify() {
  std::lock_guard l(mu_);
  cv_.notify_all();
}

void Executor::cancel() {
  canceled_.store(true);
  std::lock_guard l(mu_);
  cv_.notify_all();
}

void Executor::cancel_all() {
  std::lock_guard l(all_mu());
  for (auto* e : all_executors()) e->cancel();
}

bool Executor::signal_received() { return g_signal.load(); }

void Executor::install_signal_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (pipe(g_signal_pipe) != 0) return;
    struct sigaction sa {};
    sa.sa_handler = [](int) {
      g_signal.store(true);
      const char c = 1;
      [[maybe_unused]] auto r = write(g_signal_pipe[1], &c, 1);  // async-signal-safe wake-up
    };
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    std::thread([] {
      char c;
      while (read(g_signal_pipe[0], &c, 1) < 0) {
      }
      Executor::cancel_all();
    }).detach();
  });
}

bool Executor::can_run_inline(const CallbackGroup* g) const {
  if (tl_executor != this || tl_inline_depth >= kMaxInlineDepth) return false;
  if (opts_.threads == 1) return true;
  return g == tl_group || (g && g->type() == CallbackGroup::Type::Reentrant);
}

namespace {
// A clock's now() once per pass over the timers (they mostly share one clock): every executed item passes over all
// timers twice, and with 10 timers a clock read per timer was the largest user-space cost in `perf`.
struct ClockReads {
  const Clock* clock = nullptr;
  int64_t ns = 0;
  int64_t now(const std::shared_ptr<Clock>& c) {
    if (c.get() != clock) clock = c.get(), ns = c->now().ns;
    return ns;
  }
};
}  // namespace

void Executor::collect_due_timers_locked() {
  ClockReads now;
  for (auto& t : timers_) {
    if (t->queued_ || t->canceled() || !t->enabled()) continue;
    if (now.now(t->clock()) >= t->next_due_.load()) {
      t->queued_ = true;
      push_locked(t);
    }
  }
}

std::chrono::steady_clock::time_point Executor::next_timer_wakeup_locked() const {
  auto best = std::chrono::steady_clock::time_point::max();
  const auto now = std::chrono::steady_clock::now();
  ClockReads clock_now;
  for (const auto& t : timers_) {
    if (t->queued_ || t->canceled()) continue;
    if (t->clock()->type() == ClockType::Ros && t->clock()->sim_time_active()) continue;  // woken by notify()
    const int64_t dt = t->next_due_.load() - clock_now.now(t->clock());
    best = std::min(best, now + std::chrono::nanoseconds(std::max<int64_t>(dt, 0)));
  }
  return best;
}

bool Executor::run_one(std::unique_lock<std::mutex>& lock, Time*) {
  collect_due_timers_locked();
  std::size_t n = size_;
  for (std::size_t i = 0; i < n; ++i) {
    auto e = pop_locked();
    CallbackGroup* g = e->group();
    const bool exclusive = g && g->type() == CallbackGroup::Type::MutuallyExclusive;
    if (exclusive && g->busy_) {
      blocked_.push_back(std::move(e));
      continue;
    }
    if (exclusive) g->busy_ = true;
    lock.unlock();
    const Executor* prev_exec = tl_executor;
    const CallbackGroup* prev_group = tl_group;
    tl_executor = this;
    tl_group = g;
    e->run();
    tl_executor = prev_exec;
    tl_group = prev_group;
    executed_.fetch_add(1, std::memory_order_relaxed);
    lock.lock();
    if (exclusive) {
      g->busy_ = false;
      if (!blocked_.empty()) {
        for (auto& b : blocked_) push_locked(std::move(b));
        blocked_.clear();
        if (sleeping_ > 0) cv_.notify_all();
      }
    }
    if (auto* t = dynamic_cast<TimerBase*>(e.get())) t->queued_ = false;
    return true;
  }
  return false;
}

void Executor::worker(const std::function<bool()>* pred, std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mu_);
  bool worked = false;
  while (!canceled_.load()) {
    if (pred) {
      lock.unlock();
      const bool done = (*pred)();
      lock.lock();
      if (done) return;
    }
    if (run_one(lock, nullptr)) {
      worked = true;
      continue;
    }
    if (worked && opts_.spin.count() > 0) {
      // poll briefly for the next item before paying for a sleep and a wake-up
      worked = false;
      lock.unlock();
      const auto until = std::min(deadline, std::chrono::steady_clock::now() + opts_.spin);
      while (ready_count_.load(std::memory_order_acquire) == 0 && std::chrono::steady_clock::now() < until &&
             !canceled_.load(std::memory_order_relaxed)) {
        __builtin_ia32_pause();
      }
      lock.lock();
      continue;
    }
    auto wake = std::min(next_timer_wakeup_locked(), deadline);
    // a predicate may depend on state outside this executor (discovery, other threads): re-check it often
    if (pred) wake = std::min(wake, std::chrono::steady_clock::now() + std::chrono::milliseconds(5));
    if (std::chrono::steady_clock::now() >= deadline) return;
    ++sleeping_;
    if (wake == std::chrono::steady_clock::time_point::max()) {
      cv_.wait(lock);
    } else {
      cv_.wait_until(lock, wake);
    }
    --sleeping_;
  }
}

void Executor::spin() {
  std::vector<std::thread> extra;
  for (std::size_t i = 1; i < opts_.threads; ++i) {
    extra.emplace_back([this] { worker(nullptr, std::chrono::steady_clock::time_point::max()); });
  }
  worker(nullptr, std::chrono::steady_clock::time_point::max());
  for (auto& t : extra) t.join();
}

bool Executor::spin_until(const std::function<bool()>& pred, std::chrono::nanoseconds timeout) {
  worker(&pred, std::chrono::steady_clock::now() + timeout);
  return pred();
}

void Executor::spin_for(std::chrono::nanoseconds duration) {
  worker(nullptr, std::chrono::steady_clock::now() + duration);
}

void Executor::enter_inline() { ++tl_inline_depth; }
void Executor::leave_inline() { --tl_inline_depth; }

}  // namespace cairn
