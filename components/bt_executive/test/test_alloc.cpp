// Issue 8 performance goal as a regression test: no heap allocation per tick in steady state (counted with a
// replaced global operator new; deterministic, no timing).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "cairn/bt_executive/xml_loader.hpp"

static std::atomic<std::uint64_t> g_allocs{0};
void* operator new(std::size_t n) {
  g_allocs.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace cairn::bt;

namespace {

TEST(Allocations, NoAllocationPerTickInSteadyState) {
  NodeFactory f;
  const char* xml = R"(<root BTCPP_format="4"><BehaviorTree ID="M">
    <KeepRunningUntilFailure><ReactiveSequence>
      <ScriptCondition code="x &lt; 1000000"/>
      <Fallback>
        <Inverter><AlwaysSuccess/></Inverter>
        <Sequence _skipIf="x &lt; 0">
          <Script code="x := x + 1; y := x * 0.5"/>
          <Switch2 variable="{mode}" case_1="1" case_2="2">
            <Timeout msec="100"><Sleep msec="10"/></Timeout>
            <Delay delay_msec="5"><AlwaysSuccess/></Delay>
            <Parallel success_count="1"><Sleep msec="7"/><Sleep msec="9"/></Parallel>
          </Switch2>
          <RetryUntilSuccessful num_attempts="3"><ForceSuccess><AlwaysFailure/></ForceSuccess></RetryUntilSuccessful>
        </Sequence>
      </Fallback>
    </ReactiveSequence></KeepRunningUntilFailure></BehaviorTree></root>)";
  auto bb = Blackboard::create();
  bb->set<std::int64_t>("x", 0);
  bb->set<std::int64_t>("mode", 1);
  LoadOptions o;
  o.blackboard = bb;
  ManualScheduler sched;  // must outlive the tree: destroying a tree halts it, which cancels timers
  Tree t = loadTreeFromText(f, xml, o);
  t.setScheduler(&sched);
  std::uint64_t events = 0;
  t.addObserver([&](const TransitionEvent&) { ++events; });
  auto step = [&](int k) {
    if (k % 300 == 150) bb->set<std::int64_t>("mode", (k / 300) % 3);  // visit every branch
    sched.advanceBy(std::chrono::milliseconds(3));
    sched.fireDueTimers();
    ASSERT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  };
  for (int k = 0; k < 1000; ++k) step(k);  // warm-up: vectors reach their capacity
  const std::uint64_t a0 = g_allocs.load(), e0 = events;
  for (int k = 1000; k < 4000; ++k) step(k);
  EXPECT_EQ(g_allocs.load() - a0, 0u);
  EXPECT_GT(events - e0, 10000u);  // the tree really did work
  EXPECT_GT(bb->get<std::int64_t>("x"), 100);
}

}  // namespace
