// Semantics of every control and decorator (including halting and reactivity), preconditions, async actions,
// blackboard typing/remapping/concurrency and the event stream.
#include <gtest/gtest.h>

#include <sstream>
#include <thread>

#include "test_nodes.hpp"

using namespace cairn::bt;
using namespace cairn::bt::testing;

namespace {

class Engine : public ::testing::Test {
 protected:
  void SetUp() override { g_journal = &journal; }
  void TearDown() override { g_journal = nullptr; }
  Tree load(const std::string& body, std::shared_ptr<Blackboard> bb = nullptr) {
    LoadOptions o;
    o.blackboard = bb;
    Tree t = loadTreeFromText(factory, wrap(body), o);
    t.setScheduler(&sched);
    return t;
  }
  Journal journal;
  NodeFactory factory = makeFactory();
  ManualScheduler sched;
};

TEST_F(Engine, SequenceResumesAtRunningChildAndFailsAtFirstFailure) {
  Tree t = load(R"(<Sequence><TestSync name="a"/><TestAsync name="b" ticks="2"/><TestSync name="c"/></Sequence>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("a.tick"), 1u);  // not re-ticked while b runs (Stüde Alg. 5.1 + memory of BT.CPP)
  EXPECT_EQ(journal.count("c.tick"), 1u);
  for (auto& n : t.nodes()) EXPECT_EQ(n->status(), n.get() == t.root() ? NodeStatus::SUCCESS : NodeStatus::IDLE);

  Tree f = load(R"(<Sequence><TestSync name="x" result="FAILURE"/><TestSync name="y"/></Sequence>)");
  EXPECT_EQ(f.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(journal.count("y.tick"), 0u);
}

TEST_F(Engine, SequenceWithMemoryRetriesOnlyTheFailedChild) {
  auto bb = Blackboard::create();
  bb->set<bool>("ok", false);
  Tree t = load(R"(<SequenceWithMemory><TestSync name="a"/><TestCond name="c" flag="{ok}"/></SequenceWithMemory>)", bb);
  EXPECT_EQ(t.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(t.tickOnce(), NodeStatus::FAILURE);
  bb->set<bool>("ok", true);
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("a.tick"), 1u);
  EXPECT_EQ(journal.count("c.tick"), 3u);

  journal.events.clear();
  Tree s = load(R"(<Sequence><TestSync name="a"/><TestSync name="b" result="FAILURE"/></Sequence>)");
  s.tickOnce();
  s.tickOnce();
  EXPECT_EQ(journal.count("a.tick"), 2u);  // the memoryless sequence starts over
}

TEST_F(Engine, FallbackStopsAtFirstSuccess) {
  Tree t = load(R"(<Fallback><TestSync name="a" result="FAILURE"/><TestSync name="b"/><TestSync name="c"/></Fallback>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.events, (std::vector<std::string>{"a.tick", "b.tick"}));
  Tree f = load(R"(<Fallback><AlwaysFailure/><AlwaysFailure/></Fallback>)");
  EXPECT_EQ(f.tickOnce(), NodeStatus::FAILURE);
}

TEST_F(Engine, ReactiveSequenceReevaluatesConditionAndHaltsOnFailure) {
  auto bb = Blackboard::create();
  bb->set<bool>("ok", true);
  Tree t = load(R"(<ReactiveSequence><TestCond name="c" flag="{ok}"/><TestAsync name="A" ticks="10"/></ReactiveSequence>)", bb);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(journal.count("c.tick"), 3u);
  EXPECT_EQ(journal.count("A.start"), 1u);  // a condition in front does not disturb the running action
  bb->set<bool>("ok", false);
  EXPECT_EQ(t.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(journal.count("A.halt"), 1u);
  EXPECT_EQ(journal.active, 0);
}

// Regression modelled on BehaviorTree.CPP issue #1031: when a reactive control switches from one running child
// to another, BT.CPP starts the new child (onStart) before halting the old one, so two actions run at once.
TEST_F(Engine, Issue1031ReactiveFallbackHaltsOldChildBeforeStartingNew) {
  auto bb = Blackboard::create();
  bb->set<bool>("door_open", false);
  Tree t = load(R"(
    <ReactiveFallback>
      <Sequence><TestCond name="door" flag="{door_open}"/><TestAsync name="GoThrough" ticks="5"/></Sequence>
      <TestAsync name="OpenDoor" ticks="5"/>
    </ReactiveFallback>)", bb);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);  // door closed -> OpenDoor runs
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(journal.count("OpenDoor.start"), 1u);
  bb->set<bool>("door_open", true);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);  // switch to GoThrough
  const auto halt = journal.indexOf("OpenDoor.halt");
  const auto start = journal.indexOf("GoThrough.start");
  ASSERT_GE(halt, 0);
  ASSERT_GE(start, 0);
  EXPECT_LT(halt, start);
  EXPECT_EQ(journal.max_active, 1);  // at most one RUNNING child at any instant
  EXPECT_EQ(t.findByPath("ReactiveFallback/OpenDoor")->status(), NodeStatus::IDLE);
}

TEST_F(Engine, Issue1031ReactiveSequenceNeverRunsTwoChildren) {
  auto bb = Blackboard::create();
  bb->set<bool>("a", true);
  // Child 1 is a fallback that starts an async action whenever `a` turns false while child 2 runs.
  Tree t = load(R"(
    <ReactiveSequence>
      <Fallback><TestCond name="ca" flag="{a}"/><TestAsync name="FixA" ticks="2"/></Fallback>
      <TestAsync name="Work" ticks="50"/>
    </ReactiveSequence>)", bb);
  for (int k = 0; k < 30; ++k) {
    bb->set<bool>("a", (k % 5) != 3);
    t.tickOnce();
    int running_children = 0;
    for (TreeNode* c : t.root()->children()) running_children += c->status() == NodeStatus::RUNNING;
    EXPECT_LE(running_children, 1);
  }
  EXPECT_EQ(journal.max_active, 1);
  EXPECT_GT(journal.count("FixA.start"), 1u);
  EXPECT_GT(journal.count("Work.halt"), 1u);
}

TEST_F(Engine, ParallelThresholds) {
  Tree t = load(R"(<Parallel success_count="2" failure_count="2">
      <TestAsync name="a" ticks="1"/><TestAsync name="b" ticks="3"/><TestAsync name="c" ticks="5"/></Parallel>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);  // a done
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);  // b done -> 2 successes, c halted
  EXPECT_EQ(journal.count("c.halt"), 1u);
  EXPECT_EQ(journal.count("a.start"), 1u);       // completed children are not re-ticked

  Tree f = load(R"(<Parallel failure_count="1"><TestAsync name="d" ticks="1" result="FAILURE"/><TestAsync name="e" ticks="9"/></Parallel>)");
  EXPECT_EQ(f.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(f.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(journal.count("e.halt"), 1u);

  Tree all = load(R"(<Parallel><AlwaysSuccess/><TestAsync name="g" ticks="1"/></Parallel>)");
  EXPECT_EQ(all.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(all.tickOnce(), NodeStatus::SUCCESS);
}

TEST_F(Engine, IfThenElseAndWhileDoElse) {
  auto bb = Blackboard::create();
  bb->set<bool>("c", true);
  Tree ite = load(R"(<IfThenElse><TestCond name="c" flag="{c}"/><TestAsync name="then" ticks="2"/><TestAsync name="else" ticks="1"/></IfThenElse>)", bb);
  EXPECT_EQ(ite.tickOnce(), NodeStatus::RUNNING);
  bb->set<bool>("c", false);
  EXPECT_EQ(ite.tickOnce(), NodeStatus::RUNNING);  // not reactive: condition not re-evaluated
  EXPECT_EQ(ite.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("c.tick"), 1u);
  EXPECT_EQ(journal.count("else.start"), 0u);
  EXPECT_EQ(ite.tickOnce(), NodeStatus::RUNNING);  // now the else branch
  EXPECT_EQ(journal.count("else.start"), 1u);

  journal = Journal{};
  bb->set<bool>("c", true);
  Tree wde = load(R"(<WhileDoElse><TestCond name="w" flag="{c}"/><TestAsync name="do" ticks="9"/><TestAsync name="other" ticks="9"/></WhileDoElse>)", bb);
  EXPECT_EQ(wde.tickOnce(), NodeStatus::RUNNING);
  bb->set<bool>("c", false);
  EXPECT_EQ(wde.tickOnce(), NodeStatus::RUNNING);
  EXPECT_LT(journal.indexOf("do.halt"), journal.indexOf("other.start"));
  EXPECT_EQ(journal.max_active, 1);

  Tree two = load(R"(<WhileDoElse><AlwaysFailure/><AlwaysSuccess/></WhileDoElse>)");
  EXPECT_EQ(two.tickOnce(), NodeStatus::FAILURE);
}

TEST_F(Engine, SwitchSelectsCaseAndHaltsPreviousBranch) {
  Tree t = load(R"(<Sequence>
      <Switch3 variable="{mode}" case_1="1" case_2="dock" case_3="2.5">
        <TestAsync name="one" ticks="9"/><TestAsync name="dock" ticks="9"/><TestAsync name="half" ticks="9"/>
        <TestAsync name="default" ticks="9"/>
      </Switch3></Sequence>)");
  auto bb = t.rootBlackboard();
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);  // unset -> default
  EXPECT_EQ(journal.count("default.start"), 1u);
  bb->set<Value>("mode", Value(std::int64_t{1}));
  t.tickOnce();
  EXPECT_LT(journal.indexOf("default.halt"), journal.indexOf("one.start"));
  bb->set<Value>("mode", Value(std::string("dock")));
  t.tickOnce();
  bb->set<Value>("mode", Value(2.5));
  t.tickOnce();
  EXPECT_EQ(journal.count("dock.start"), 1u);
  EXPECT_EQ(journal.count("half.start"), 1u);
  EXPECT_EQ(journal.max_active, 1);
}

TEST_F(Engine, InverterAndForce) {
  EXPECT_EQ(load("<Inverter><AlwaysSuccess/></Inverter>").tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(load("<Inverter><AlwaysFailure/></Inverter>").tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(load("<ForceSuccess><AlwaysFailure/></ForceSuccess>").tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(load("<ForceFailure><AlwaysSuccess/></ForceFailure>").tickOnce(), NodeStatus::FAILURE);
  Tree r = load(R"(<Inverter><TestAsync name="a" ticks="1"/></Inverter>)");
  EXPECT_EQ(r.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(r.tickOnce(), NodeStatus::FAILURE);
}

TEST_F(Engine, RetryAndRepeatCount) {
  Tree t = load(R"(<Sequence><Script code="n := 0"/>
      <RetryUntilSuccessful num_attempts="5"><ScriptCondition code="n += 1; n >= 3"/></RetryUntilSuccessful></Sequence>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(t.rootBlackboard()->get<std::int64_t>("n"), 3);

  Tree f = load(R"(<Sequence><Script code="n := 0"/>
      <Retry num_attempts="2"><ScriptCondition code="n += 1; n >= 3"/></Retry></Sequence>)");
  EXPECT_EQ(f.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(f.rootBlackboard()->get<std::int64_t>("n"), 2);

  Tree r = load(R"(<Sequence><Script code="n := 0"/><Repeat num_cycles="4"><Script code="n += 1"/></Repeat></Sequence>)");
  EXPECT_EQ(r.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(r.rootBlackboard()->get<std::int64_t>("n"), 4);

  // Forever: one cycle per tick, never blocks a tick.
  Tree inf = load(R"(<Sequence><Script code="n := 0"/><Repeat num_cycles="-1"><Script code="n += 1"/></Repeat></Sequence>)");
  for (int k = 0; k < 5; ++k) EXPECT_EQ(inf.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(inf.rootBlackboard()->get<std::int64_t>("n"), 5);

  // Async child: the event loop jumps from timer to timer; two 10 ms sleeps end at 20 ms.
  Tree async = load(R"(<Repeat num_cycles="2"><Sleep msec="10"/></Repeat>)");
  EXPECT_EQ(runUntilComplete(async, sched, 100), NodeStatus::SUCCESS);
  EXPECT_EQ(sched.now(), TimePoint{std::chrono::milliseconds(20)});
}

TEST_F(Engine, TimeoutHaltsSlowChildOnSchedulerTime) {
  Tree t = load(R"(<Timeout msec="50"><Sleep msec="100"/></Timeout>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  ASSERT_EQ(sched.pendingTimers(), 2u);  // timeout + sleep
  EXPECT_EQ(sched.nextTimer(), TimePoint{std::chrono::milliseconds(50)});
  sched.advanceTo(std::chrono::milliseconds(50));
  EXPECT_EQ(t.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(t.findByPath("Timeout/Sleep")->status(), NodeStatus::IDLE);
  sched.fireDueTimers();
  EXPECT_EQ(sched.pendingTimers(), 0u);  // the halted Sleep cancelled its timer

  ManualScheduler s2;
  Tree ok = load(R"(<Timeout msec="100"><Sleep msec="30"/></Timeout>)");
  EXPECT_EQ(runUntilComplete(ok, s2), NodeStatus::SUCCESS);
  EXPECT_EQ(s2.now(), TimePoint{std::chrono::milliseconds(30)});
}

TEST_F(Engine, DelayTicksChildOnlyAfterDelay) {
  Tree t = load(R"(<Delay delay_msec="40"><TestSync name="x"/></Delay>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  sched.advanceTo(std::chrono::milliseconds(39));
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(journal.count("x.tick"), 0u);
  sched.advanceTo(std::chrono::milliseconds(40));
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("x.tick"), 1u);
}

TEST_F(Engine, KeepRunningUntilFailureAndRunOnce) {
  Tree k = load(R"(<Sequence><Script code="n := 0"/><KeepRunningUntilFailure><ScriptCondition code="n += 1; n &lt; 3"/></KeepRunningUntilFailure></Sequence>)");
  EXPECT_EQ(k.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(k.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(k.tickOnce(), NodeStatus::FAILURE);

  Tree once = load(R"(<Sequence><RunOnce><TestSync name="x"/></RunOnce><TestSync name="y"/></Sequence>)");
  EXPECT_EQ(once.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(once.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("x.tick"), 1u);
  EXPECT_EQ(journal.count("y.tick"), 2u);
  Tree once2 = load(R"(<RunOnce then_skip="false"><AlwaysFailure/></RunOnce>)");
  EXPECT_EQ(once2.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(once2.tickOnce(), NodeStatus::FAILURE);
  Tree once3 = load(R"(<RunOnce><AlwaysFailure/></RunOnce>)");
  EXPECT_EQ(once3.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(once3.tickOnce(), NodeStatus::SKIPPED);
}

TEST_F(Engine, PreconditionsSkipFailSucceedAndWhile) {
  Tree t = load(R"(<Sequence><Script code="A := 1"/>
      <TestSync name="a" _skipIf="A == 1"/>
      <TestSync name="b" _successIf="A == 2" _failureIf="A != 1"/>
      <TestSync name="c" _onSuccess="B := A + 10"/></Sequence>)");
  TraceRecorder rec(t);
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("a.tick"), 0u);
  EXPECT_EQ(journal.count("b.tick"), 1u);
  EXPECT_TRUE(rec.has("1 Sequence/a IDLE -> SKIPPED"));
  EXPECT_EQ(t.rootBlackboard()->get<std::int64_t>("B"), 11);

  Tree f = load(R"(<Sequence><Script code="A := 3"/><TestSync name="b" _failureIf="A != 1"/></Sequence>)");
  EXPECT_EQ(f.tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(journal.count("b.tick"), 1u);

  Tree all = load(R"(<Sequence><AlwaysFailure _skipIf="true"/><AlwaysFailure _skipIf="1 &lt; 2"/></Sequence>)");
  EXPECT_EQ(all.tickOnce(), NodeStatus::SKIPPED);

  auto bb = Blackboard::create();
  bb->set<bool>("go", true);
  Tree w = load(R"(<Sequence><TestAsync name="x" ticks="9" _while="go" _onHalted="halted := true"/></Sequence>)", bb);
  EXPECT_EQ(w.tickOnce(), NodeStatus::RUNNING);
  bb->set<bool>("go", false);
  EXPECT_EQ(w.tickOnce(), NodeStatus::SKIPPED);
  EXPECT_EQ(journal.count("x.halt"), 1u);
  EXPECT_TRUE(bb->get<bool>("halted"));
}

TEST_F(Engine, HaltTreeHaltsEveryRunningNodeAndCancelsTimers) {
  Tree t = load(R"(<Parallel success_count="2"><TestAsync name="a" ticks="9"/>
      <Timeout msec="500"><Sleep msec="100"/></Timeout><Delay delay_msec="50"><AlwaysSuccess/></Delay></Parallel>)");
  TraceRecorder rec(t);
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(sched.pendingTimers(), 3u);  // timeout, sleep, delay
  t.haltTree();
  EXPECT_EQ(journal.count("a.halt"), 1u);
  EXPECT_EQ(sched.pendingTimers(), 0u);
  for (const auto& n : t.nodes()) EXPECT_EQ(n->status(), NodeStatus::IDLE) << n->path();
  // children are halted before their parent, in index order
  const auto& l = rec.lines;
  auto idx = [&](const std::string& s) { return std::find(l.begin(), l.end(), s) - l.begin(); };
  EXPECT_LT(idx("1 Parallel/a RUNNING -> IDLE"), idx("1 Parallel/Timeout/Sleep RUNNING -> IDLE"));
  EXPECT_LT(idx("1 Parallel/Timeout/Sleep RUNNING -> IDLE"), idx("1 Parallel/Timeout RUNNING -> IDLE"));
  EXPECT_LT(idx("1 Parallel/Delay RUNNING -> IDLE"), idx("1 Parallel RUNNING -> IDLE"));
}

TEST_F(Engine, SkippedChildrenInControls) {
  EXPECT_EQ(load(R"(<Fallback><AlwaysSuccess _skipIf="true"/><AlwaysFailure _skipIf="true"/></Fallback>)").tickOnce(),
            NodeStatus::SKIPPED);
  EXPECT_EQ(load(R"(<Fallback><AlwaysSuccess _skipIf="true"/><AlwaysFailure/></Fallback>)").tickOnce(),
            NodeStatus::FAILURE);
  EXPECT_EQ(load(R"(<Parallel><AlwaysFailure _skipIf="true"/><AlwaysSuccess/></Parallel>)").tickOnce(),
            NodeStatus::SUCCESS);  // skipped children do not count towards "all"
  EXPECT_EQ(load(R"(<Inverter><AlwaysFailure _skipIf="true"/></Inverter>)").tickOnce(), NodeStatus::SKIPPED);
  EXPECT_EQ(load(R"(<ReactiveSequence><AlwaysFailure _skipIf="true"/><AlwaysSuccess/></ReactiveSequence>)").tickOnce(),
            NodeStatus::SUCCESS);
}

TEST_F(Engine, PreconditionParallelAllAndUpdateTracking) {
  Tree p = load(R"(<Sequence><Script code="a := 1"/>
      <Precondition if="a == 2" else="SKIPPED"><TestSync name="x"/></Precondition>
      <Precondition if="a == 1"><TestSync name="y"/></Precondition></Sequence>)");
  EXPECT_EQ(p.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("x.tick"), 0u);
  EXPECT_EQ(journal.count("y.tick"), 1u);

  Tree pa = load(R"(<ParallelAll max_failures="2"><TestAsync name="a" ticks="1" result="FAILURE"/>
      <TestAsync name="b" ticks="3"/></ParallelAll>)");
  EXPECT_EQ(pa.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(pa.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(pa.tickOnce(), NodeStatus::RUNNING);
  EXPECT_EQ(pa.tickOnce(), NodeStatus::SUCCESS);  // one failure < max_failures, after both completed
  EXPECT_EQ(journal.count("b.halt"), 0u);

  Tree u = load(R"(<Sequence><WasEntryUpdated entry="{goal}"/>
      <SkipUnlessUpdated entry="{goal}"><TestSync name="plan"/></SkipUnlessUpdated></Sequence>)");
  auto bb = u.rootBlackboard();
  EXPECT_EQ(u.tickOnce(), NodeStatus::FAILURE);
  bb->set<Value>("goal", Value(std::int64_t{3}));
  EXPECT_EQ(u.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("plan.tick"), 1u);
  EXPECT_EQ(u.tickOnce(), NodeStatus::FAILURE);  // not written again
  EXPECT_EQ(journal.count("plan.tick"), 1u);
}

TEST_F(Engine, ScriptRuntimeErrorFailsTheNodeWithoutThrowing) {
  Tree t = load(R"(<Script code="y := x + 1"/>)");
  std::vector<std::string> errors;
  t.context().setErrorHandler([&](const RuntimeErrorEvent& e) { errors.push_back(e.message); });
  EXPECT_EQ(t.tickOnce(), NodeStatus::FAILURE);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("'x' is unset"), std::string::npos);
}

/// Async action driven by an outside "executor event": the reply arrives on another thread.
class ServiceCall : public EventActionNode {
 public:
  using EventActionNode::EventActionNode;
  std::thread worker;
  ~ServiceCall() override {
    if (worker.joinable()) worker.join();
  }

 protected:
  NodeStatus start(std::uint64_t run) override {
    if (worker.joinable()) worker.join();
    worker = std::thread([this, run] { complete(run, NodeStatus::SUCCESS); });
    return NodeStatus::RUNNING;
  }
};

TEST_F(Engine, EventActionCompletedFromAnotherThreadRequestsTick) {
  factory.registerNodeType<ServiceCall>("ServiceCall");
  Tree t = load(R"(<Sequence><ServiceCall name="call"/></Sequence>)");
  EXPECT_EQ(t.tickOnce(), NodeStatus::RUNNING);
  auto* node = dynamic_cast<ServiceCall*>(t.findByPath("Sequence/call"));
  ASSERT_NE(node, nullptr);
  node->worker.join();
  EXPECT_TRUE(sched.takeTickRequest());  // the reply asked for a tick
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_FALSE(node->complete(node->currentRun() - 1, NodeStatus::FAILURE));  // stale replies are ignored
}

TEST_F(Engine, BlackboardTypedEntriesAndRemapping) {
  auto bb = Blackboard::create();
  bb->set<int>("n", 5);
  EXPECT_THROW(bb->declare<std::string>("n"), BlackboardError);
  EXPECT_EQ(bb->declare<int>("n")->sequence(), 1u);
  auto child = Blackboard::create(bb);
  child->addRemap("m", "n");
  EXPECT_EQ(child->get<int>("m"), 5);
  child->set<int>("private", 1);
  EXPECT_EQ(bb->getEntry("private"), nullptr);
  EXPECT_EQ(child->get<int>("@n"), 5);
  auto autoc = Blackboard::create(bb);
  autoc->setAutoRemap(true);
  autoc->set<int>("shared", 2);
  autoc->set<int>("_local", 3);
  EXPECT_EQ(bb->get<int>("shared"), 2);
  EXPECT_EQ(bb->getEntry("_local"), nullptr);
}

TEST_F(Engine, BlackboardConcurrentAccessNeverTears) {
  struct Pair {
    std::int64_t a = 0, b = 0;
  };
  auto bb = Blackboard::create();
  auto e = bb->declare<Pair>("p");
  std::atomic<bool> stop{false};
  std::thread writer([&] {
    for (std::int64_t i = 1; i <= 200000; ++i) e->set(Pair{i, -i});
    stop = true;
  });
  std::size_t torn = 0, reads = 0;
  while (!stop) {
    Pair p;
    if (e->tryGet(p)) {
      ++reads;
      torn += p.a != -p.b;
    }
  }
  writer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(e->sequence(), 200000u);
}

TEST_F(Engine, TransitionStreamAndFileLoggerReplay) {
  Tree t = load(R"(<Sequence><AlwaysSuccess/><Sleep msec="20"/><AlwaysSuccess/></Sequence>)");
  std::stringstream log;
  TraceRecorder rec(t);
  {
    FileLogger logger(t, log);
    EXPECT_EQ(runUntilComplete(t, sched), NodeStatus::SUCCESS);
  }
  EXPECT_TRUE(rec.has("1 Sequence/AlwaysSuccess#0 IDLE -> SUCCESS"));
  EXPECT_TRUE(rec.has("2 Sequence/Sleep RUNNING -> SUCCESS"));
  EXPECT_TRUE(rec.has("2 Sequence/AlwaysSuccess#2 SUCCESS -> IDLE"));
  EXPECT_EQ(rec.lines.back(), "2 Sequence RUNNING -> SUCCESS");
  TraceReplay r = TraceReplay::read(log);
  ASSERT_EQ(r.transitions().size(), rec.lines.size());
  for (std::size_t i = 0; i < rec.lines.size(); ++i) {
    const auto& e = r.transitions()[i];
    EXPECT_EQ(formatTransition(e.step, r.paths()[e.uid], e.old_status, e.new_status), rec.lines[i]);
  }
  auto after1 = r.statusesAfter(1);
  EXPECT_EQ(after1[2], NodeStatus::RUNNING);  // Sleep (uid 2) running after step 1
  EXPECT_EQ(r.transitions().back().time_ns, 20'000'000);
}

}  // namespace
