// Monitoring and recovery ladders (Stüde §5.3, Table 5.1) on a simulated system: a component dies / a topic stops,
// the monitor detects it, the arbiter blocks the task, the ladder restarts the component and the task resumes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

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

/// Writes /proc/<pid>/stat and statm of a fake process under `root`.
void writeFakeProc(const std::filesystem::path& root, int pid, unsigned long long utime, unsigned long long stime,
                   unsigned long long resident_pages) {
  std::filesystem::create_directories(root / std::to_string(pid));
  std::ofstream(root / std::to_string(pid) / "stat")
      << pid << " (cairn container (x)) S 1 " << pid << " " << pid << " 0 -1 4194560 100 0 0 0 " << utime << " "
      << stime << " 0 0 20 0 3 0 100 123456 789\n";
  std::ofstream(root / std::to_string(pid) / "statm") << 50000 << " " << resident_pages << " 300 10 0 4000 0\n";
}

TEST(Monitoring, ProcessMonitorReadsCpuAndRssFromFakeProc) {
  const auto root = std::filesystem::temp_directory_path() / ("cairn_fake_proc_" + std::to_string(getpid()));
  std::filesystem::remove_all(root);
  ValueMonitor cpu("cpu:main", "resource", "main", Band{.warn_high = 50, .error_high = 90});
  ValueMonitor ram("ram:main", "resource", "main", Band{.warn_high = 100, .error_high = 200});
  ProcessMonitor pm(cpu, ram, ProcessSampler::Options{root.string(), 100, 4096});
  EXPECT_FALSE(pm.sample(TimePoint(0s)));  // no pid yet
  pm.setPid(4242);
  EXPECT_FALSE(pm.sample(TimePoint(0s)));  // no such process
  writeFakeProc(root, 4242, 1000, 200, 12800);  // 12 s of CPU, 12800 pages of 4 KiB = 50 MB
  ASSERT_TRUE(pm.sample(TimePoint(1s)));
  EXPECT_EQ(cpu.evaluate({}).message, "no sample yet");  // CPU % needs two samples
  EXPECT_NEAR(ram.evaluate({}).value, 50.0, 1e-9);
  EXPECT_EQ(ram.evaluate({}).level, Level::Ok);
  writeFakeProc(root, 4242, 1060, 210, 30000);  // +0.7 s of CPU in 1 s: 70 %; 117 MB
  ASSERT_TRUE(pm.sample(TimePoint(2s)));
  EXPECT_NEAR(cpu.evaluate({}).value, 70.0, 1e-9);
  EXPECT_EQ(cpu.evaluate({}).level, Level::Warning);
  EXPECT_EQ(ram.evaluate({}).level, Level::Warning);
  writeFakeProc(root, 4242, 1250, 210, 60000);  // +1.9 s in 2 s: 95 %; 234 MB
  ASSERT_TRUE(pm.sample(TimePoint(4s)));
  EXPECT_NEAR(cpu.evaluate({}).value, 95.0, 1e-9);
  EXPECT_EQ(cpu.evaluate({}).level, Level::Error);
  EXPECT_EQ(ram.evaluate({}).level, Level::Error);
  // A respawned container is a new pid: its CPU history starts over (no difference across processes).
  writeFakeProc(root, 4343, 5, 5, 100);
  pm.setPid(4343);
  ASSERT_TRUE(pm.sample(TimePoint(5s)));
  EXPECT_NEAR(cpu.evaluate({}).value, 95.0, 1e-9);  // unchanged until the second sample of the new pid
  writeFakeProc(root, 4343, 15, 5, 100);
  ASSERT_TRUE(pm.sample(TimePoint(6s)));
  EXPECT_NEAR(cpu.evaluate({}).value, 10.0, 1e-9);
  // Truncated and garbage files are "not read", never a crash.
  std::ofstream(root / "4343" / "stat") << "4343 (x) S 1 2";
  EXPECT_FALSE(pm.sample(TimePoint(7s)));
  std::ofstream(root / "4343" / "stat") << "garbage";
  EXPECT_FALSE(pm.sample(TimePoint(8s)));
  std::filesystem::remove_all(root);

  ProcessSampler self(getpid());  // the real /proc
  EXPECT_TRUE(self.sample(TimePoint(0s)).ok);
  const auto s1 = self.sample(TimePoint(1s));
  EXPECT_TRUE(s1.ok && s1.has_cpu);
  EXPECT_GT(s1.rss_mb, 0.1);
}

TEST(Monitoring, ClockOffsetIsTheLowerEnvelopeOfReceiveMinusStamp) {
  ClockOffsetMonitor clock("clock:/peer", "peer", 20ms, 100ms, 2s);
  EXPECT_EQ(clock.evaluate(TimePoint(0s)).level, Level::Ok);  // no samples
  // The peer's clock is 30 ms behind ours; latencies 2..12 ms (seeded pattern), one 400 ms delay spike.
  for (int k = 0; k < 20; ++k) {
    const TimePoint sent_local = TimePoint(k * 100ms);
    const auto latency = std::chrono::milliseconds(k == 7 ? 400 : 2 + (k * 7) % 11);
    clock.onStamp(sent_local - 30ms, sent_local + latency);
  }
  double off = 0;
  ASSERT_TRUE(clock.estimate(TimePoint(2s), off));
  EXPECT_NEAR(off, 0.032, 1e-9);  // offset + the smallest latency in the window (2 ms), the spike ignored
  EXPECT_EQ(clock.evaluate(TimePoint(2s)).level, Level::Warning);
  // Later the peer is 150 ms ahead: once the old samples leave the window the error band is reached.
  for (int k = 0; k < 20; ++k) {
    const TimePoint sent_local = TimePoint(3s + k * 100ms);
    clock.onStamp(sent_local + 150ms, sent_local + 5ms);
  }
  const Report r = clock.evaluate(TimePoint(5s));
  EXPECT_NEAR(r.value, -0.145, 1e-9);
  EXPECT_EQ(r.level, Level::Error);
  EXPECT_EQ(r.category, "resource");
  EXPECT_FALSE(clock.estimate(TimePoint(10s), off));  // window empty again
}

TEST(Monitoring, ConfigurationsAsDataSelectMonitorsAndRequiredComponents) {
  MonitorSet set;
  set.emplace<NavigationMonitor>({}, "navigation", 1, 1);
  set.emplace<AgeMonitor>({}, "alive:/slam", "component", "/slam", 1s, 2s);
  set.emplace<AgeMonitor>({}, "alive:/dock", "component", "/dock", 1s, 2s);
  set.emplace<TopicRateMonitor>({}, "/scan", "/laser", 10.0);
  set.emplace<ValueMonitor>({}, "cpu:main", "resource", "main", Band{.error_high = 90});
  set.defineConfigurations({"operating: navigation /slam rate:/scan", "charging: /dock", "mapping: /slam rate:/scan"},
                           "monitor.configurations");
  EXPECT_EQ(set.configurationNames(), (std::set<std::string>{"charging", "mapping", "operating"}));
  auto names = [&] {
    std::vector<std::string> n;
    for (const auto& r : set.evaluate(TimePoint(0s))) n.push_back(r.monitor);
    return n;
  };
  set.setConfiguration("operating");
  EXPECT_EQ(names(), (std::vector<std::string>{"navigation", "alive:/slam", "rate:/scan", "cpu:main"}));
  EXPECT_EQ(set.requiredComponents(), std::vector<std::string>{"/slam"});
  set.setConfiguration("charging");  // no navigation monitor while docked; the dock must run, SLAM need not
  EXPECT_EQ(names(), (std::vector<std::string>{"alive:/dock", "cpu:main"}));  // cpu: named nowhere, so everywhere
  EXPECT_EQ(set.requiredComponents(), std::vector<std::string>{"/dock"});
  EXPECT_FALSE(set.active(*set.find("navigation")));
  EXPECT_THROW(set.setConfiguration("dancing"), std::invalid_argument);
  EXPECT_EQ(set.configuration(), "charging");

  auto error = [](std::vector<std::string> entries) {
    MonitorSet s;
    s.emplace<NavigationMonitor>({}, "navigation", 1, 1);
    try {
      s.defineConfigurations(entries, "monitor.configurations");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error({"operating: navigation", "charging: /dock"}),
            "monitor.configurations[1]: unknown monitor '/dock' (known: navigation)");
  EXPECT_EQ(error({"operating navigation"}),
            "monitor.configurations[0]: expected '<configuration>: <monitor or component> ...', got 'operating navigation'");
  EXPECT_EQ(error({"a b: navigation"}),
            "monitor.configurations[0]: expected '<configuration>: <monitor or component> ...', got 'a b: navigation'");
  EXPECT_EQ(error({"a: navigation", "a:"}), "monitor.configurations[1]: configuration 'a' defined twice");
  EXPECT_EQ(error({"operating: navigation", "charging:"}), "no error");  // a configuration without monitors
}

/// A simulated robot: components alive or dead, a 10 Hz topic from "camera", recoveries that take one tick.
struct SimSystem : RecoveryInterface {
  std::map<std::string, bool> alive{{"camera", true}, {"slam", true}};
  std::vector<std::string> calls;
  std::vector<Done> pending;
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

// Table 5.1's navigation ladder. Only a goal reached clears "k failures in a row", so every step ends with a retry
// (the task runs again); a failed retry escalates: wait, move backwards, ask the supervisor. Before, the steps
// re-checked an error nothing could clear while the task was blocked, and the supervisor's all-clear was followed
// by the same error again (the fake supervisor here reset the monitor, which the real one does not).
TEST_F(MonitoredRun, NavigationLadderRetriesAndEscalates) {
  for (int k = 0; k < 25; ++k) step();
  // One navigation failure (error at 1), then the ladder until the task runs again.
  auto fail_and_recover = [&](const char* what) {
    nav->onResult(false);
    for (int k = 0; k < 3; ++k) step();
    EXPECT_TRUE(blocked()) << what;
    const std::int64_t at_block = work();
    for (int k = 0; k < 200 && blocked(); ++k) step();
    EXPECT_FALSE(blocked()) << what << ": the task was not released for its retry";
    for (int k = 0; k < 5; ++k) step();
    EXPECT_GT(work(), at_block) << what << ": the task did not run again";
  };
  fail_and_recover("first failure");
  EXPECT_TRUE(sys.calls.empty()) << "step 1 only waits";
  fail_and_recover("the retry failed");
  EXPECT_EQ(sys.calls, std::vector<std::string>{"backwards"});
  fail_and_recover("the second retry failed");
  EXPECT_EQ(sys.calls, (std::vector<std::string>{"backwards", "supervisor:3 consecutive navigation failures"}));
  // The next goal is reached: no error, and a later failure starts the ladder from the beginning.
  nav->onResult(true);
  for (int k = 0; k < 5; ++k) step();
  EXPECT_FALSE(blocked());
  EXPECT_EQ(nav->attempts(), 0);
  fail_and_recover("a new failure after a success");
  EXPECT_EQ(sys.calls.size(), 2u) << "waits again, no second move backwards";
  EXPECT_EQ(tree.rootBlackboard()->get<std::int64_t>("recoveries"), 4);
}

TEST_F(MonitoredRun, ResourceErrorsOnlyAlertOnce) {
  for (int k = 0; k < 25; ++k) step();
  cpu->update(97.0);
  for (int k = 0; k < 5; ++k) step();
  EXPECT_EQ(sys.calls, std::vector<std::string>{"alert:cpu:slam = 97"});
  EXPECT_FALSE(blocked());
}

TEST_F(MonitoredRun, ConfigurationSwitchedOnTheBlackboardDisablesTheNavigationMonitor) {
  monitors.setRequiredComponents("charging", {"dock"});
  for (int k = 0; k < 25; ++k) step();
  tree.rootBlackboard()->set<std::string>("configuration", "charging");  // e.g. the task's "go charging" branch
  step();
  EXPECT_EQ(monitors.configuration(), "charging");
  EXPECT_EQ(monitors.requiredComponents(), std::vector<std::string>{"dock"});
  nav->onResult(false);  // a navigation error while docked is not an error of the charging configuration
  for (int k = 0; k < 10; ++k) step();
  EXPECT_FALSE(blocked());
  EXPECT_TRUE(sys.calls.empty());
  tree.rootBlackboard()->set<std::string>("configuration", "dancing");  // unknown: one alert, configuration kept
  for (int k = 0; k < 3; ++k) step();
  EXPECT_EQ(sys.calls, std::vector<std::string>{"alert:monitor configuration: unknown configuration 'dancing' "
                                                "(defined: charging, operating)"});
  EXPECT_EQ(monitors.configuration(), "charging");
  tree.rootBlackboard()->set<std::string>("configuration", "operating");
  step();
  EXPECT_TRUE(blocked());  // back in operation the pending navigation error blocks the task
}

}  // namespace
