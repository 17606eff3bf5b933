// Monitoring and recovery ladders (Stüde §5.3, Table 5.1) on a simulated system: a component dies / a topic stops,
// the monitor detects it, the arbiter blocks the task, the ladder restarts the component and the task resumes.
#include <gtest/gtest.h>

#include <unistd.h>

#include "cairn/bt_executive/monitoring.hpp"
#include "cairn/bt_executive/xml_loader.hpp"

using namespace cairn::bt;
using namespace cairn::bt::monitoring;
using namespace std::chrono_literals;

namespace {

TEST(Monitoring, BandsAndMonitors) {
  Band b{.warn_low = 8, .warn_high = 12, .error_low = 5, .error_high = 15};
  EXPECT_EQ(b.classify(10), Level::Ok);
  EXPECT_EQ(b.classify(13), Level::Warning);
  EXPECT_EQ(b.classify(4), Level::Error);

  TopicRateMonitor rate("/scan", "laser", 10.0);
  for (int k = 0; k < 30; ++k) rate.onMessage(TimePoint(k * 100ms));
  EXPECT_EQ(rate.evaluate(TimePoint(2900ms)).level, Level::Ok);
  EXPECT_NEAR(rate.rate(TimePoint(2900ms)), 10.0, 0.51);
  EXPECT_EQ(rate.evaluate(TimePoint(3600ms)).level, Level::Warning);  // 13 msgs in the last 2 s: 6.5 Hz
  EXPECT_EQ(rate.evaluate(TimePoint(5000ms)).level, Level::Error);    // silent topic

  AgeMonitor age("loc", "localization", "slam", 10s, 30s);
  age.heartbeat(TimePoint(0s));
  EXPECT_EQ(age.evaluate(TimePoint(5s)).level, Level::Ok);
  EXPECT_EQ(age.evaluate(TimePoint(15s)).level, Level::Warning);
  EXPECT_EQ(age.evaluate(TimePoint(31s)).level, Level::Error);

  NavigationMonitor nav("navigation", 1, 2);
  nav.onResult(false);
  EXPECT_EQ(nav.evaluate({}).level, Level::Warning);
  nav.onResult(false);
  EXPECT_EQ(nav.evaluate({}).level, Level::Error);
  nav.onResult(true);
  EXPECT_EQ(nav.evaluate({}).level, Level::Ok);

  ProcessSampler self(getpid());
  auto s0 = self.sample(TimePoint(0s));
  EXPECT_TRUE(s0.ok);
  EXPECT_GT(s0.rss_mb, 0.1);
}

TEST(Monitoring, ConfigurationsSelectMonitors) {
  MonitorSet set;
  set.emplace<NavigationMonitor>({"operating"}, "navigation", 1, 1);
  set.emplace<AgeMonitor>({"mapping", "operating"}, "slam_alive", "component", "slam", 1s, 2s);
  set.setRequiredComponents("charging", {"dock"});
  static_cast<NavigationMonitor*>(set.find("navigation"))->onResult(false);
  EXPECT_EQ(set.evaluate(TimePoint(10s)).size(), 2u);
  EXPECT_EQ(MonitorSet::worstBlocking(set.evaluate(TimePoint(10s))).category, "component");  // priority
  set.setConfiguration("charging");
  EXPECT_TRUE(set.evaluate(TimePoint(10s)).empty());
  EXPECT_EQ(set.requiredComponents(), std::vector<std::string>{"dock"});
}

/// A simulated robot: components alive or dead, a 10 Hz topic from "camera", recoveries that take one tick.
struct SimSystem : RecoveryInterface {
  std::map<std::string, bool> alive{{"camera", true}, {"slam", true}};
  std::vector<std::string> calls;
  std::vector<Done> pending;
  bool supervisor_fixes_nav = true;
  NavigationMonitor* nav = nullptr;
  void restartComponent(const std::string& c, Done d) override {
    calls.push_back("restart:" + c);
    alive[c] = true;
    pending.push_back(std::move(d));
  }
  void moveBackwards(double, Done d) override {
    calls.push_back("backwards");
    pending.push_back(std::move(d));
  }
  void slowRotate(double, Done d) override {
    calls.push_back("rotate");
    pending.push_back(std::move(d));
  }
  void askSupervisor(const std::string& m, Done d) override {
    calls.push_back("supervisor:" + m);
    if (nav && supervisor_fixes_nav) nav->reset({});
    pending.push_back(std::move(d));
  }
  void sendAlert(const std::string& m) override { calls.push_back("alert:" + m); }
  void completeAll() {
    auto p = std::move(pending);
    pending.clear();
    for (auto& d : p) d(true);
  }
};

class MonitoredRun : public ::testing::Test {
 protected:
  void SetUp() override {
    rate = &monitors.emplace<TopicRateMonitor>({"operating"}, "/camera/image", "camera", 10.0);
    nav = &monitors.emplace<NavigationMonitor>({"operating"}, "navigation", 1, 1);
    cpu = &monitors.emplace<ValueMonitor>({"operating"}, "cpu:slam", "resource", "slam", Band{.error_high = 90});
    sys.nav = nav;
    registerMonitoringNodes(factory, monitors, sys);
    const std::string xml = "<root BTCPP_format=\"4\" main_tree_to_execute=\"MonitoredExecution\">"
                            "<include path=\"" + monitoringTreesPath() + "\"/>"
                            "<BehaviorTree ID=\"Task\"><KeepRunningUntilFailure>"
                            "<Script code=\"@work := @work + 1\"/></KeepRunningUntilFailure></BehaviorTree></root>";
    auto bb = Blackboard::create();
    bb->set<std::int64_t>("work", 0);
    LoadOptions o;
    o.blackboard = bb;
    tree = loadTreeFromText(factory, xml, o, "monitored.xml");
    tree.setScheduler(&sched);
    bb->set<int>("settle_ms", 500);
  }
  /// 100 ms steps: camera publishes while alive, recoveries complete on the next step.
  NodeStatus step() {
    now += 100ms;
    sched.advanceTo(now);
    if (sys.alive["camera"]) rate->onMessage(now);
    sys.completeAll();
    return tree.tickOnce();
  }
  std::int64_t work() { return tree.rootBlackboard()->get<std::int64_t>("work"); }
  bool blocked() { return tree.rootBlackboard()->get<bool>("task_blocked"); }

  MonitorSet monitors;
  SimSystem sys;
  NodeFactory factory;
  ManualScheduler sched;
  TopicRateMonitor* rate = nullptr;
  NavigationMonitor* nav = nullptr;
  ValueMonitor* cpu = nullptr;
  Tree tree;
  TimePoint now{0};
};

TEST_F(MonitoredRun, KilledComponentIsRestartedAndTaskResumes) {
  for (int k = 0; k < 30; ++k) ASSERT_EQ(step(), NodeStatus::RUNNING);
  const auto before = work();
  EXPECT_GT(before, 25);
  EXPECT_FALSE(blocked());

  sys.alive["camera"] = false;  // kill the component: its topic stops
  int detect_steps = 0;
  while (!blocked() && detect_steps < 50) {
    step();
    ++detect_steps;
  }
  ASSERT_TRUE(blocked());
  EXPECT_GE(detect_steps, 10);  // rate falls below the error band (5 Hz) only after ~1 s of a 2 s window
  const auto at_block = work();
  int blocked_steps = 0;
  while (blocked() && blocked_steps < 100) {
    EXPECT_EQ(step(), NodeStatus::RUNNING);
    EXPECT_TRUE(!blocked() || work() == at_block);  // the task does not run while blocked
    ++blocked_steps;
  }
  EXPECT_FALSE(blocked());
  EXPECT_EQ(sys.calls, std::vector<std::string>{"restart:camera"});
  EXPECT_TRUE(sys.alive["camera"]);
  for (int k = 0; k < 10; ++k) step();
  EXPECT_GT(work(), at_block + 5);  // resumed
  EXPECT_EQ(tree.rootBlackboard()->get<std::int64_t>("recoveries"), 1);
}

TEST_F(MonitoredRun, NavigationLadderEscalatesToSupervisor) {
  for (int k = 0; k < 25; ++k) step();
  nav->onResult(false);  // persistent navigation error: waiting and moving back do not clear it
  for (int k = 0; k < 200 && sys.calls.size() < 2; ++k) step();
  ASSERT_EQ(sys.calls.size(), 2u);
  EXPECT_EQ(sys.calls[0], "backwards");  // after wait-and-retry (5 s Sleep) failed
  EXPECT_EQ(sys.calls[1], "supervisor:1 consecutive navigation failures");
  for (int k = 0; k < 5; ++k) step();
  EXPECT_FALSE(blocked());  // the supervisor's all-clear released the task
}

TEST_F(MonitoredRun, ResourceErrorsOnlyAlertOnce) {
  for (int k = 0; k < 25; ++k) step();
  cpu->update(97.0);
  for (int k = 0; k < 5; ++k) step();
  EXPECT_EQ(sys.calls, std::vector<std::string>{"alert:cpu:slam = 97"});
  EXPECT_FALSE(blocked());
}

}  // namespace
