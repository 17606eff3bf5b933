// Executors: an event queue of ready work items, served by one or more threads.
//
// Work arrives as Executable pointers pushed by whoever made them ready (an intra-process publisher,
// a DDS listener, a service reply, a timer coming due). There is no wait set to rebuild: an idle
// executor sleeps on a condition variable until the next timer or the next event. When the publishing
// thread *is* an executor thread of the subscriber and callback-group rules allow it, delivery runs
// inline instead (no queue, no wake-up).
#ifndef CAIRN_EXECUTOR_HPP
#define CAIRN_EXECUTOR_HPP

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "cairn/clock.hpp"

namespace cairn {

class Executor;

class CallbackGroup {
 public:
  /// MutuallyExclusive: one callback of the group at a time; Reentrant: any number at once.
  /// Immediate: subscription callbacks run on the thread that delivers the message (the publisher's thread
  /// intra-process, Cyclone's receive thread for DDS) without going through an executor; the lowest
  /// latency path (as ddsperf's listener mode), for short, thread-safe callbacks only.
  enum class Type { MutuallyExclusive, Reentrant, Immediate };
  explicit CallbackGroup(Type t = Type::MutuallyExclusive) : type_(t) {}
  Type type() const { return type_; }

 private:
  friend class Executor;
  Type type_;
  bool busy_ = false;  // guarded by the executor's mutex
};

/// One entity with pending work (a subscription, timer, service...). run() executes one unit.
class Executable : public std::enable_shared_from_this<Executable> {
 public:
  explicit Executable(std::shared_ptr<CallbackGroup> group) : group_(std::move(group)) {}
  virtual ~Executable() = default;
  CallbackGroup* group() const { return group_.get(); }
  /// Runs one unit of work unless disabled. Serialised with disable().
  void run() {
    guarded([this] { execute(); });
  }
  /// Runs `f` under the same guard as run() (used for inline delivery of a message).
  template <class F>
  void guarded(F&& f) {
    std::lock_guard l(run_mu_);
    if (enabled_.load(std::memory_order_acquire)) f();
  }
  /// After disable() returns, no callback of this entity is running or will run (safe to destroy
  /// what the callbacks use). May be called from the entity's own callback.
  void disable();
  bool enabled() const { return enabled_.load(std::memory_order_acquire); }

 protected:
  virtual void execute() = 0;

 private:
  std::shared_ptr<CallbackGroup> group_;
  std::recursive_mutex run_mu_;
  std::atomic<bool> enabled_{true};
};

class TimerBase : public Executable {
 public:
  TimerBase(std::shared_ptr<CallbackGroup> g, std::shared_ptr<Clock> clock, std::chrono::nanoseconds period,
            std::function<void()> cb);
  std::chrono::nanoseconds period() const { return period_; }
  /// A one-shot timer fires once, `period` after creation (or after reset()), then cancels itself.
  void set_one_shot(bool on) { one_shot_ = on; }
  void cancel() { canceled_ = true; }
  bool canceled() const { return canceled_; }
  void reset();
  /// Time of the next expiry on the timer's clock.
  Time next_due() const { return Time{next_due_.load()}; }
  const std::shared_ptr<Clock>& clock() const { return clock_; }

 protected:
  void execute() override;

 private:
  friend class Executor;
  std::shared_ptr<Clock> clock_;
  std::chrono::nanoseconds period_;
  std::function<void()> cb_;
  std::atomic<int64_t> next_due_;
  std::atomic<bool> canceled_{false};
  bool one_shot_ = false;
  bool queued_ = false;  // guarded by the executor's mutex
};

class Executor {
 public:
  struct Options {
    std::size_t threads = 1;  ///< 1 = single-threaded executor
    /// After running work, a thread polls for more work this long before it sleeps on the condition
    /// variable: a message arriving in that window costs no wake-up (futex) on either side. 0 = never spin.
    std::chrono::nanoseconds spin{0};
  };
  Executor();
  explicit Executor(Options opts);
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  /// Thread-safe: `e` has one more unit of work ready.
  void schedule(const std::shared_ptr<Executable>& e);
  void add_timer(const std::shared_ptr<TimerBase>& t);
  void remove_timer(const TimerBase* t);
  /// Re-evaluates timers (a simulated clock moved).
  void notify();
  /// Runs `fn` once on an executor thread, within `group` (null: a group of its own). Thread-safe; the
  /// cheap way for another thread (an async reply, a behavior tree's requestTick) to get work done here.
  void post(std::function<void()> fn, std::shared_ptr<CallbackGroup> group = nullptr);

  /// Serves work with `threads` threads (the calling one included) until cancel() or shutdown.
  void spin();
  /// Serves work until `pred()` holds or `timeout` passes; returns pred(). Single calling thread; `pred`
  /// is re-checked after every callback and at least every 5 ms.
  bool spin_until(const std::function<bool()>& pred, std::chrono::nanoseconds timeout);
  /// Runs ready work and due timers for at most `duration` (single calling thread).
  void spin_for(std::chrono::nanoseconds duration);
  void cancel();
  bool canceled() const { return canceled_.load(); }
  /// Timers this executor serves (added and not removed).
  std::size_t timer_count() const;

  /// True when the calling thread is serving this executor and a callback of `g` may run right
  /// here without breaking callback-group exclusion.
  bool can_run_inline(const CallbackGroup* g) const;
  /// Runs `f` (one callback of an entity in group `g`) inline on this executor thread.
  template <class F>
  void run_inline(F&& f) const {
    enter_inline();
    f();
    leave_inline();
  }
  std::size_t threads() const { return opts_.threads; }
  std::uint64_t executed_count() const { return executed_.load(std::memory_order_relaxed); }

  /// Cancels every executor of the process (SIGINT/SIGTERM handler uses this).
  static void cancel_all();
  /// Installs SIGINT/SIGTERM handlers that cancel all executors (idempotent).
  static void install_signal_handlers();
  static bool signal_received();

 private:
  static void enter_inline();
  static void leave_inline();
  bool run_one(std::unique_lock<std::mutex>& lock, Time* wake_hint);
  void worker(const std::function<bool()>* pred, std::chrono::steady_clock::time_point deadline);
  void collect_due_timers_locked();
  std::chrono::steady_clock::time_point next_timer_wakeup_locked() const;

  Options opts_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  // ring buffer of ready items (grows, never shrinks: no allocation in steady state)
  std::vector<std::shared_ptr<Executable>> ring_;
  std::size_t head_ = 0, size_ = 0;
  std::vector<std::shared_ptr<Executable>> blocked_;  // ready but their group is busy
  std::vector<std::shared_ptr<TimerBase>> timers_;
  /// Wakes this executor when a simulated clock of its timers moves: one update callback per clock (not per
  /// timer: a behavior tree's one-shot timers used to add one each, never removed), unregistered in ~Executor.
  struct ClockHook;
  std::shared_ptr<ClockHook> clock_hook_;
  std::vector<std::pair<std::shared_ptr<Clock>, std::uint64_t>> hooked_clocks_;  // guarded by mu_
  std::atomic<bool> canceled_{false};
  std::atomic<std::uint64_t> executed_{0};
  std::size_t sleeping_ = 0;
  std::atomic<std::size_t> ready_count_{0};  // size_, readable without the lock (spinning threads)

  void push_locked(std::shared_ptr<Executable> e);
  std::shared_ptr<Executable> pop_locked();
};

}  // namespace cairn

#endif  // CAIRN_EXECUTOR_HPP
