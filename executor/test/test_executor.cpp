#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "cairn/executor.hpp"
#include "cairn/node.hpp"
#include "cairn/testing.hpp"

using namespace std::chrono_literals;
using cairn::CallbackGroup;
using cairn::Executor;

namespace {
class Counter : public cairn::Executable {
 public:
  using Executable::Executable;
  std::atomic<int> runs{0};
  std::function<void()> body;

 protected:
  void execute() override {
    ++runs;
    if (body) body();
  }
};
}  // namespace

TEST(Executor, RunsScheduledWorkAndTimers) {
  Executor exec;
  auto c = std::make_shared<Counter>(std::make_shared<CallbackGroup>());
  exec.schedule(c);
  exec.schedule(c);
  int ticks = 0;
  auto t = std::make_shared<cairn::TimerBase>(std::make_shared<CallbackGroup>(),
                                              std::make_shared<cairn::Clock>(cairn::ClockType::Steady), 5ms,
                                              [&] { ++ticks; });
  exec.add_timer(t);
  EXPECT_TRUE(exec.spin_until([&] { return ticks >= 3 && c->runs == 2; }, 5s));
  EXPECT_EQ(c->runs, 2);
}

TEST(Executor, SimTimeTimersFollowTheSimulatedClock) {
  Executor exec;
  auto clock = std::make_shared<cairn::Clock>(cairn::ClockType::Ros);
  clock->enable_sim_time(true);
  clock->set_sim_time(cairn::Time{0});
  std::atomic<int> ticks{0};
  auto t = std::make_shared<cairn::TimerBase>(std::make_shared<CallbackGroup>(), clock, 100ms, [&] { ++ticks; });
  exec.add_timer(t);
  exec.spin_for(50ms);
  EXPECT_EQ(ticks, 0) << "no sim time passed, the timer must not fire";
  std::thread feeder([&] {
    for (int i = 1; i <= 10; ++i) {
      std::this_thread::sleep_for(2ms);
      clock->set_sim_time(cairn::Time{i * 50'000'000LL});  // 50 ms of sim time per step
      // Each period's tick before the clock moves on: a starved executor thread would otherwise see two periods
      // pass at once and fire once for them (a timer does not replay missed periods), under ctest -j2 load.
      for (int k = 0; k < 1000 && ticks < i / 2; ++k) std::this_thread::sleep_for(2ms);
    }
  });
  exec.spin_until([&] { return ticks >= 5; }, 5s);
  feeder.join();
  EXPECT_EQ(ticks, 5) << "500 ms of sim time = 5 periods of 100 ms";
}

// A behavior tree starts a one-shot timer per Wait; each used to register a clock update callback that was
// never removed (the demo's executive grew by ~1 MB/h, and every sim-time update called them all).
TEST(Executor, TimersOnASimClockShareOneClockCallbackThatGoesWithTheExecutor) {
  auto clock = std::make_shared<cairn::Clock>(cairn::ClockType::Ros);
  clock->enable_sim_time(true);
  {
    Executor exec;
    auto group = std::make_shared<CallbackGroup>();
    for (int i = 0; i < 1000; ++i) {
      auto t = std::make_shared<cairn::TimerBase>(group, clock, 10ms, [] {});
      t->set_one_shot(true);
      exec.add_timer(t);
      exec.remove_timer(t.get());
    }
    EXPECT_EQ(clock->update_callbacks(), 1u);
    std::atomic<int> ticks{0};
    auto t = std::make_shared<cairn::TimerBase>(group, clock, 100ms, [&] { ++ticks; });
    exec.add_timer(t);
    std::thread feeder([&] {
      for (int i = 1; i <= 3; ++i) {
        std::this_thread::sleep_for(2ms);
        clock->set_sim_time(cairn::Time{i * 100'000'000LL});
        // As above: one period per step, and the step's tick before the next (failed once under ctest -j2 with
        // 2 ticks: two steps 2 ms apart reached a starved executor as one).
        for (int k = 0; k < 1000 && ticks < i; ++k) std::this_thread::sleep_for(2ms);
      }
    });
    exec.spin_until([&] { return ticks >= 3; }, 5s);
    feeder.join();
    EXPECT_EQ(ticks, 3);  // the shared callback still wakes the executor when sim time moves
  }
  EXPECT_EQ(clock->update_callbacks(), 0u);
  clock->set_sim_time(cairn::Time{1'000'000'000LL});  // no executor left to call
}

TEST(Executor, MutuallyExclusiveGroupNeverRunsTwoCallbacksAtOnce) {
  Executor exec(Executor::Options{4});
  auto group = std::make_shared<CallbackGroup>(CallbackGroup::Type::MutuallyExclusive);
  std::atomic<int> inside{0}, max_inside{0}, done{0};
  std::vector<std::shared_ptr<Counter>> items;
  for (int i = 0; i < 8; ++i) {
    auto c = std::make_shared<Counter>(group);
    c->body = [&] {
      int now = ++inside;
      int m = max_inside;
      while (now > m && !max_inside.compare_exchange_weak(m, now)) {
      }
      std::this_thread::sleep_for(2ms);
      --inside;
      ++done;
    };
    items.push_back(c);
  }
  std::thread spinner([&] { exec.spin(); });
  for (int round = 0; round < 5; ++round)
    for (auto& c : items) exec.schedule(c);
  while (done < 40) std::this_thread::sleep_for(1ms);
  exec.cancel();
  spinner.join();
  EXPECT_EQ(max_inside, 1);
}

TEST(Executor, ReentrantGroupRunsInParallel) {
  Executor exec(Executor::Options{2});
  auto group = std::make_shared<CallbackGroup>(CallbackGroup::Type::Reentrant);
  std::atomic<int> inside{0}, max_inside{0}, done{0};
  std::vector<std::shared_ptr<Counter>> items;
  for (int i = 0; i < 2; ++i) {
    auto c = std::make_shared<Counter>(group);
    c->body = [&] {
      int now = ++inside;
      int m = max_inside;
      while (now > m && !max_inside.compare_exchange_weak(m, now)) {
      }
      // wait (bounded) until the other one is inside too
      for (int k = 0; k < 2000 && max_inside < 2; ++k) std::this_thread::sleep_for(1ms);
      --inside;
      ++done;
    };
    items.push_back(c);
  }
  std::thread spinner([&] { exec.spin(); });
  for (auto& c : items) exec.schedule(c);
  while (done < 2) std::this_thread::sleep_for(1ms);
  exec.cancel();
  spinner.join();
  EXPECT_EQ(max_inside, 2);
}

TEST(Executor, DisableWaitsForTheRunningCallbackAndStopsFurtherRuns) {
  Executor exec(Executor::Options{2});
  auto c = std::make_shared<Counter>(std::make_shared<CallbackGroup>());
  std::atomic<bool> entered{false};
  std::atomic<bool> finished{false};
  c->body = [&] {
    entered = true;
    std::this_thread::sleep_for(30ms);
    finished = true;
  };
  std::thread spinner([&] { exec.spin(); });
  exec.schedule(c);
  while (!entered) std::this_thread::sleep_for(1ms);
  c->disable();
  EXPECT_TRUE(finished) << "disable() returned while the callback was still running";
  exec.schedule(c);
  std::this_thread::sleep_for(20ms);
  exec.cancel();
  spinner.join();
  EXPECT_EQ(c->runs, 1);
}

TEST(Executor, PostRunsOnTheExecutorThreadAndOneShotTimersFireOnce) {
  Executor exec;
  std::thread::id where;
  bool posted = false;
  std::thread other([&] { exec.post([&] { where = std::this_thread::get_id(); posted = true; }); });
  other.join();
  exec.spin_until([&] { return posted; }, 5s);
  EXPECT_TRUE(posted);
  EXPECT_EQ(where, std::this_thread::get_id());
  int fired = 0;
  auto t = std::make_shared<cairn::TimerBase>(std::make_shared<CallbackGroup>(),
                                              std::make_shared<cairn::Clock>(cairn::ClockType::Steady), 2ms,
                                              [&] { ++fired; });
  t->set_one_shot(true);
  exec.add_timer(t);
  exec.spin_for(30ms);
  EXPECT_EQ(fired, 1);
  t->reset();
  exec.spin_for(30ms);
  EXPECT_EQ(fired, 2) << "reset() re-arms a one-shot timer";
}

TEST(Executor, ANodeKeepsNoTimerThatCanNeverRunAgain) {
  // A node keeps what it creates, but a fired one-shot timer whose handle was dropped can never run again: kept,
  // a node creating one-shot timers (a timeout per request) grew its list and its executor's without bound, and
  // the executor passes over every timer for every item it runs.
  Executor exec;
  cairn::NodeOptions o("timers", &exec);
  o.start_parameter_services = false;
  cairn::Node node(o);
  int periodic = 0, fired = 0;
  node.create_wall_timer(1ms, [&] { ++periodic; });  // handle dropped: still the node's, still running
  auto held = node.create_one_shot_timer(1ms, [&] { ++fired; });
  for (int i = 0; i < 300; ++i) {
    node.create_one_shot_timer(1ms, [&] { ++fired; });
    if (i % 10 == 9) exec.spin_until([&] { return fired == i + 2; }, 5s);
  }
  exec.spin_until([&] { return fired == 301; }, 5s);
  EXPECT_EQ(fired, 301);
  node.create_one_shot_timer(1h, [] {});  // a creation drops what has fired meanwhile
  EXPECT_LE(exec.timer_count(), 4u) << "fired one-shot timers nobody holds must go";
  // what can still run stays: the periodic timer, and the fired one-shot timer whose handle is held
  const int before = periodic;
  exec.spin_until([&] { return periodic > before; }, 5s);
  EXPECT_GT(periodic, before);
  held->reset();
  exec.spin_until([&] { return fired == 302; }, 5s);
  EXPECT_EQ(fired, 302) << "a held one-shot timer can be re-armed";
}

// The test main reserves this process's DDS domain (cairn/testing.hpp): the lock on its file is held, so no other
// process -- and no second reservation in this one -- can take it; every reservation is another free domain.
TEST(TestingMain, EachProcessHoldsItsDomainAndEachReservationIsAnotherOne) {
  const int mine = std::atoi(std::getenv("CAIRN_DOMAIN_ID"));
  ASSERT_GE(mine, 1);
  ASSERT_LE(mine, 230);
  const int a = cairn::testing::reserve_test_domain(), b = cairn::testing::reserve_test_domain();
  for (const int d : {a, b}) {
    EXPECT_GE(d, 1);
    EXPECT_LE(d, 230);
    EXPECT_NE(d, mine);
  }
  EXPECT_NE(a, b);
  if (std::getenv("CAIRN_TEST_DOMAIN_ID")) GTEST_SKIP() << "domain forced by CAIRN_TEST_DOMAIN_ID: not reserved";
  const auto path = std::filesystem::temp_directory_path() / ("cairn_test_domain_" + std::to_string(mine) + ".lock");
  const int fd = open(path.c_str(), O_RDWR | O_CLOEXEC);
  ASSERT_GE(fd, 0) << path;
  EXPECT_NE(flock(fd, LOCK_EX | LOCK_NB), 0) << "the domain's lock is not held";
  close(fd);
}
