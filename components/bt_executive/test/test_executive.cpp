// The runtime-agnostic executive: load/start/stop/switch, event-driven ticking, status protocol round trip.
#include <gtest/gtest.h>

#include "cairn/bt_executive/executive.hpp"
#include "cairn/bt_executive/trace.hpp"
#include "cairn/bt_executive/xml_loader.hpp"

using namespace cairn::bt;

namespace {

const std::string kData = CAIRN_BT_TEST_DATA;

TEST(Executive, LifecycleAndEventDrivenTicks) {
  NodeFactory f;
  ManualScheduler sched;
  Executive ex(f, sched);
  EXPECT_FALSE(ex.start());
  EXPECT_EQ(ex.state(), Executive::State::Empty);
  ex.load(kData + "/trace_demo.xml");
  EXPECT_EQ(ex.treeId(), "Main");  // several trees in the file; main_tree_to_execute chose Main
  EXPECT_EQ(ex.state(), Executive::State::Ready);
  EXPECT_EQ(ex.tick(), NodeStatus::IDLE);  // not started: no tick
  ASSERT_TRUE(ex.start());
  // Event-driven loop: tick, then jump to the next timer (what the component's executor does with real timers).
  int ticks = 0;
  while (ex.tick() == NodeStatus::RUNNING && ticks < 100) {
    ++ticks;
    auto t = sched.nextTimer();
    ASSERT_TRUE(t.has_value());
    sched.advanceTo(*t);
    sched.fireDueTimers();
  }
  EXPECT_EQ(ex.state(), Executive::State::Finished);
  EXPECT_EQ(ex.lastStatus(), NodeStatus::SUCCESS);
  EXPECT_LE(ticks, 6);  // timers only: far fewer ticks than a 20 ms periodic loop (5 x 20 ms = 100 ms of sleeps)
  const std::string events = ex.eventsJson();
  EXPECT_NE(events.find("{\"step\":1,\"t_ns\":0,\"uid\":0,\"from\":\"IDLE\",\"to\":\"RUNNING\"}"), std::string::npos);
  EXPECT_EQ(ex.eventsJson(), "{\"tree\":\"Main\",\"dropped\":0,\"events\":[]}");

  // Restart, stop in the middle: running async nodes are halted and their timers cancelled.
  ASSERT_TRUE(ex.start());
  EXPECT_EQ(ex.tick(), NodeStatus::RUNNING);
  EXPECT_GT(sched.pendingTimers(), 0u);
  ex.stop();
  EXPECT_EQ(ex.state(), Executive::State::Stopped);
  sched.fireDueTimers();
  EXPECT_EQ(sched.pendingTimers(), 0u);
  for (const auto& n : ex.tree()->nodes()) EXPECT_EQ(n->status(), NodeStatus::IDLE);
}

TEST(Executive, SwitchTreeAndKeepTreeOnLoadError) {
  NodeFactory f;
  ManualScheduler sched;
  Executive ex(f, sched);
  ex.load(kData + "/success.xml", "OnlyTree");
  ex.start();
  EXPECT_EQ(ex.tick(), NodeStatus::SUCCESS);
  ex.switchTree("Check");
  EXPECT_EQ(ex.treeId(), "Check");
  EXPECT_EQ(ex.state(), Executive::State::Ready);
  EXPECT_THROW(ex.load(kData + "/cycle.xml"), LoadError);
  EXPECT_EQ(ex.treeId(), "Check");  // still the previous tree
  ex.start();
  EXPECT_EQ(ex.tick(), NodeStatus::FAILURE);  // 'n' is unset in the Check tree alone
}

TEST(Executive, StatusJsonRoundTripRendersLikeTheTrace) {
  NodeFactory f;
  ManualScheduler sched;
  Executive ex(f, sched);
  ex.load(kData + "/main_with_include.xml");
  ex.start();
  ex.tick();
  const StatusSnapshot s = parseStatusJson(ex.statusJson());
  EXPECT_EQ(s.state, "finished");
  EXPECT_EQ(s.step, 1u);
  ASSERT_EQ(s.paths.size(), ex.tree()->nodes().size());
  for (std::size_t i = 0; i < s.paths.size(); ++i) {
    EXPECT_EQ(s.paths[i], ex.tree()->nodes()[i]->path());
    EXPECT_EQ(s.statuses[i], ex.tree()->nodes()[i]->status());
  }
  EXPECT_NE(renderTree(s.paths, s.statuses).find("Sequence  SUCCESS"), std::string::npos);
  EXPECT_THROW(parseStatusJson("{\"nodes\":[{\"uid\":1,\"path\":\"x\",\"status\":\"IDLE\"}]}"), std::runtime_error);
  EXPECT_THROW(parseStatusJson("{\"tree\":\"a\""), std::runtime_error);
}

}  // namespace
