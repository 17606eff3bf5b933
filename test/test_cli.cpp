// End to end through processes: `cairn launch` starting containers, the CLI against them, the DDS path
// between two containers and the supervision of an isolated component that crashes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>
#include <utility>
#include <vector>

#include "support/subprocess.hpp"

using cairn::testing::count;
using cairn::testing::run;
using cairn::testing::slurp;
using namespace std::chrono_literals;

namespace {
const std::string kCairn = CAIRN_EXE;
const std::string kSpecs = std::string(CAIRN_SOURCE_ROOT);

std::string tmp_log(const std::string& name) { return "/tmp/cairn_test_" + std::to_string(getpid()) + "_" + name + ".log"; }

int stop(pid_t pid) {
  kill(pid, SIGTERM);
  int st = 0;
  waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

bool wait_for_text(const std::string& log, const std::string& text, int n, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (count(slurp(log), text) >= n) return true;
    std::this_thread::sleep_for(50ms);
  }
  return false;
}
}  // namespace

TEST(Cli, CommandsAgainstARunningContainer) {
  const std::string log = tmp_log("cli");
  const pid_t launch = cairn::testing::start(kCairn + " launch " + kSpecs + "/launch_specs/talker_listener.yaml", log);
  ASSERT_TRUE(wait_for_text(log, "I heard", 2, 30s)) << slurp(log);

  auto r = run(kCairn + " topic list");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("/chatter std_msgs/msg/String\n"), std::string::npos) << r.output;

  r = run(kCairn + " topic echo /chatter --once");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("data: \"Hello World: "), std::string::npos) << r.output;
  EXPECT_EQ(count(r.output, "---"), 1) << r.output;

  r = run(kCairn + " topic info /chatter");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("Publisher count: 1\n  node: /talker"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Subscription count: 1\n  node: /listener"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("qos: reliable, volatile, keep_last(10)"), std::string::npos) << r.output;

  r = run(kCairn + " topic hz /chatter --duration 2.5");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("average rate: "), std::string::npos) << r.output;

  r = run(kCairn + " node list");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* n : {"/demo_container\n", "/talker\n", "/listener\n"}) EXPECT_NE(r.output.find(n), std::string::npos) << r.output;

  r = run(kCairn + " param get /talker rate_hz");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output, "10.0\n");
  r = run(kCairn + " param set /talker text Hi");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run(kCairn + " param set /talker rate_hz -3");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("outside"), std::string::npos) << r.output;
  r = run(kCairn + " param dump /talker");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("    text: \"Hi\"\n"), std::string::npos) << r.output;

  r = run(kCairn + " component load /demo_container cairn_demo::Listener --name extra -r chatter:=/elsewhere");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("as '/extra'"), std::string::npos) << r.output;
  r = run(kCairn + " component list /demo_container");
  EXPECT_NE(r.output.find("3  /extra"), std::string::npos) << r.output;
  r = run(kCairn + " component unload /demo_container 3");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // A namespace without the leading '/' is the same namespace; the remap applies to the node's resolved topic
  // (it used to be keyed "robot/chatter", so the node stayed on /robot/chatter).
  r = run(kCairn + " component load /demo_container cairn_demo::Listener --name nsl --namespace robot -r chatter:=/elsewhere");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("as '/robot/nsl'"), std::string::npos) << r.output;
  r = run(kCairn + " topic info /elsewhere");
  EXPECT_NE(r.output.find("Subscription count: 1\n  node: /robot/nsl"), std::string::npos) << r.output;
  r = run(kCairn + " component unload /demo_container 4");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run(kCairn + " component list /demo_container");
  EXPECT_EQ(r.output.find("/extra"), std::string::npos) << "unloaded: " << r.output;
  EXPECT_EQ(r.output.find("/robot/nsl"), std::string::npos) << "unloaded: " << r.output;
  r = run(kCairn + " component load /demo_container cairn_demo::Listener --namespace 9x");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--namespace: invalid namespace '9x'"), std::string::npos) << r.output;
  r = run(kCairn + " component load /demo_container cairn_demo::Nope");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("unknown component class 'cairn_demo::Nope'"), std::string::npos) << r.output;
  r = run(kCairn + " component load /demo_container cairn_demo::Talker --name t3 -p bogus:=1");
  EXPECT_EQ(r.exit_code, 1);  // refused like an unknown parameter in a launch spec
  EXPECT_NE(r.output.find("params.bogus: cairn_demo::Talker (/t3) has no such parameter"), std::string::npos) << r.output;
  EXPECT_EQ(count(r.output, "\n"), 1) << r.output;
  r = run(kCairn + " component list");
  EXPECT_NE(r.output.find("/demo_container\n  1  /talker\n  2  /listener\n"), std::string::npos) << r.output;

  // bad input to the CLI
  r = run(kCairn + " topic echo /no_such_topic --wait 0.5");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count(r.output, "\n"), 1) << "one line: " << r.output;
  EXPECT_NE(r.output.find("no publisher of /no_such_topic"), std::string::npos);
  r = run(kCairn + " topic echo /no_such_topic --full-length --wait 0.5");  // an option of echo's, not an error
  EXPECT_NE(r.output.find("no publisher of /no_such_topic"), std::string::npos) << r.output;
  r = run(kCairn + " component list /no_such_container --wait 0.5");  // not found after discovery, not the 15 s reply timeout
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count(r.output, "\n"), 1) << "one line: " << r.output;
  EXPECT_NE(r.output.find("no container /no_such_container found (its list_nodes service was not discovered within 0.5 s"),
            std::string::npos)
      << r.output;
  r = run(kCairn + " component unload no_such_container 1 --wait 0.5");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no container /no_such_container found (its unload_node service"), std::string::npos) << r.output;
  r = run(kCairn + " param get /nobody x --timeout 0.5");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("node /nobody not found"), std::string::npos) << r.output;
  r = run(kCairn + " topic frob");
  EXPECT_EQ(r.exit_code, 2);
  r = run(kCairn + " no-such-verb");
  EXPECT_EQ(r.exit_code, 2);

  EXPECT_EQ(stop(launch), 0) << "SIGTERM must stop the launch cleanly";
  EXPECT_NE(slurp(log).find("[launch]: stopping"), std::string::npos);
}

TEST(Cli, TwoContainersTalkOverDds) {
  const std::string log = tmp_log("two");
  const pid_t launch = cairn::testing::start(kCairn + " launch " + kSpecs + "/test/data/launch/two_containers.yaml", log);
  EXPECT_TRUE(wait_for_text(log, "(dds)", 5, 30s)) << slurp(log);
  EXPECT_EQ(count(slurp(log), "(intra-process)"), 0);
  EXPECT_EQ(stop(launch), 0);
}

TEST(Cli, CrashedIsolatedComponentIsRespawned) {
  const std::string log = tmp_log("crash");
  const pid_t launch = cairn::testing::start(kCairn + " launch " + kSpecs + "/test/data/launch/crash_respawn.yaml", log);
  EXPECT_TRUE(wait_for_text(log, "loaded cairn_test::Crashes as /crashes into main__crashes", 2, 40s)) << slurp(log);
  const std::string out = slurp(log);
  EXPECT_NE(out.find("container main__crashes killed by signal 11 (SIGSEGV); respawning (restart 1)"), std::string::npos)
      << out;
  // the non-isolated talker was never affected
  EXPECT_EQ(count(out, "loaded cairn_demo::Talker as /talker into main"), 1) << out;
  EXPECT_EQ(stop(launch), 0);
}

TEST(Cli, ASlowReloadHoldsUpNeitherSupervisionNorStop) {
  // A respawned container whose component takes long to load again (here: while a file exists) is loaded by the
  // supervision loop step by step: meanwhile another child is still respawned, and SIGTERM stops the launch
  // without waiting for the load. (The reload used to block the loop for up to load_timeout + 5 s.)
  const std::string tag = std::to_string(getpid());
  const std::string gate = "/tmp/cairn_test_gate_" + tag;
  const std::string spec = "/tmp/cairn_test_reload_" + tag + ".yaml";
  const std::string log = tmp_log("reload");
  std::remove(gate.c_str());
  {
    std::ofstream f(spec);
    f << "load_timeout: 120\n"
         "containers:\n  - name: slow" << tag << "\n    components:\n"
         "      - class: cairn_test::Hangs\n        params: {seconds: 120.0, while_file: " << gate << "}\n"
         "processes:\n  - name: ticker\n    cmd: [sleep, '0.2']\n    respawn: true\n    respawn_delay: 0.05\n";
  }
  const pid_t launch = cairn::testing::start(kCairn + " launch " + spec, log);
  ASSERT_TRUE(wait_for_text(log, "loaded cairn_test::Hangs as /hangs into slow" + tag, 1, 30s)) << slurp(log);
  { std::ofstream(gate.c_str()) << "hang\n"; }
  ASSERT_EQ(run("pkill -KILL -f 'container --name slo[w]" + tag + "'").exit_code, 0);
  ASSERT_TRUE(wait_for_text(log, "respawning container slow" + tag, 1, 10s)) << slurp(log);
  const int ticks = count(slurp(log), "respawning process ticker");
  EXPECT_TRUE(wait_for_text(log, "respawning process ticker", ticks + 3, 10s))
      << "no process respawned while a container reloads:\n" << slurp(log);
  EXPECT_EQ(count(slurp(log), "loaded cairn_test::Hangs as /hangs into slow" + tag), 1) << "the reload is not hanging";
  kill(launch, SIGTERM);
  int st = -1;
  for (int i = 0; i < 200 && waitpid(launch, &st, WNOHANG) == 0; ++i) std::this_thread::sleep_for(50ms);
  if (st == -1) {  // still running after 10 s: the stop waited for the load
    kill(launch, SIGKILL);
    waitpid(launch, &st, 0);
    ADD_FAILURE() << "SIGTERM did not stop the launch while a reload was hanging:\n" << slurp(log);
  } else {
    EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << slurp(log);
  }
  EXPECT_EQ(run("pgrep -f 'container --name slo[w]" + tag + "'").exit_code, 1) << "the container outlived the launch";
  std::remove(gate.c_str());
  std::remove(spec.c_str());
}

TEST(Cli, AContainerDyingDuringStartUpFollowsItsRespawnPolicy) {
  // While another container is still loading (Hangs, 2 s), an isolated component crashes 0.2 s after its load:
  // with respawn it is restarted and the launch starts up; without, the launch ends at once with one line.
  const std::string tag = std::to_string(getpid());
  const std::string spec = "/tmp/cairn_test_startup_" + tag + ".yaml";
  auto write = [&](bool respawn) {
    std::ofstream f(spec);
    f << "containers:\n  - name: up" << tag << "\n    respawn: " << (respawn ? "true" : "false") << "\n    components:\n"
         "      - class: cairn_test::Crashes\n        params: {crash_after: 0.2}\n        isolated: true\n"
         "      - class: cairn_test::Hangs\n        params: {seconds: 2.0}\n";
  };
  write(false);
  auto r = run(kCairn + " launch " + spec + " --duration 1 2>&1");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cairn: " + spec + ": container up" + tag +
                          "__crashes killed by signal 11 (SIGSEGV) during start-up; respawn is off\n"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(count(r.output, "running 2 containers"), 0) << r.output;
  write(true);
  r = run(kCairn + " launch " + spec + " --duration 1 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto respawned = r.output.find("respawning container up" + tag + "__crashes (restart 1)");
  const auto running = r.output.find("running 2 containers, 2 components");
  EXPECT_NE(respawned, std::string::npos) << r.output;
  EXPECT_NE(running, std::string::npos) << r.output;
  EXPECT_LT(respawned, running) << "respawned during start-up:\n" << r.output;
  std::remove(spec.c_str());
}

TEST(Cli, LaunchExitsNonZeroWhenAProcessFailsAndStopsWholeProcessGroups) {
  // A process that fails (not respawned) makes the launch exit 1 with one line naming it (it always exited 0, so
  // scripts/demo.sh passed with failing processes); a process's own children are stopped with it (they were left
  // running, re-parented to init).
  const std::string tag = "317." + std::to_string(getpid() % 1000);  // a sleep only this test starts
  const std::string spec = "/tmp/cairn_test_exit_" + std::to_string(getpid()) + ".yaml";
  {
    std::ofstream f(spec);
    f << "processes:\n  - name: fails\n    cmd: [sh, -c, \"exit 3\"]\n"
         "  - name: fine\n    cmd: [\"true\"]\n"
         "  - name: group\n    cmd: [sh, -c, \"sleep " << tag << " & wait\"]\n";
  }
  auto r = run(kCairn + " launch " + spec + " --duration 2");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cairn: launch: " + spec + ": 1 failed: process fails exited with code 3\n"), std::string::npos)
      << r.output;
  // ([p]: the pattern does not match the shell running pgrep)
  EXPECT_EQ(run("pgrep -f 'slee[p] " + tag + "'").exit_code, 1) << "the shell's sleep outlived the launch";
  {
    std::ofstream f(spec);
    f << "processes:\n  - name: fine\n    cmd: [\"true\"]\n";
  }
  r = run(kCairn + " launch " + spec + " --duration 1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::remove(spec.c_str());
}

TEST(Cli, InvalidSpecIsRejectedBeforeAnythingStarts) {
  const std::string spec = "/tmp/cairn_test_bad_" + std::to_string(getpid()) + ".yaml";
  {
    std::ofstream f(spec);
    f << "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n        params: {rate_hz: x}\n";
  }
  auto r = run(kCairn + " launch " + spec);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "cairn: " + spec + ":5: params: /talker: parameter 'rate_hz' expects double, got string (\"x\")\n");
  r = run(kCairn + " launch /nonexistent.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "cairn: /nonexistent.yaml:0: cannot read the file\n");
  // the demo's relative paths (urdf/...) are relative to the repository root, where the README runs it
  r = run("cd " + kSpecs + " && " + kCairn + " launch launch_specs/demo.yaml --check");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(Cli, BadOptionValuesAreOneLineErrorsBeforeAnythingStarts) {
  const std::string spec = kSpecs + "/launch_specs/talker_listener.yaml";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"container --name c1 --threads -1", "cairn: container: --threads expects an integer in [1, 64], got '-1'"},
      {"container --name c1 --threads 100000", "cairn: container: --threads expects an integer in [1, 64], got '100000'"},
      {"container --name c1 --threads 0", "cairn: container: --threads expects an integer in [1, 64], got '0'"},
      {"container --name c1 --threads abc", "cairn: container: --threads expects an integer in [1, 64], got 'abc'"},
      {"container --name c1 --load-timeout nan", "cairn: container: --load-timeout expects a number in [0.1, 3600], got 'nan'"},
      {"container --name c1 --bogus", "cairn: container: unknown argument '--bogus'"},
      {"launch " + spec + " --duration -1", "cairn: launch: --duration expects a number in [0, 1e+09], got '-1'"},
      {"launch " + spec + " --duration nan", "cairn: launch: --duration expects a number in [0, 1e+09], got 'nan'"},
      {"launch " + spec + " --duration 1e300", "cairn: launch: --duration expects a number in [0, 1e+09], got '1e300'"},
      {"launch " + spec + " --duration abc", "cairn: launch: --duration expects a number in [0, 1e+09], got 'abc'"},
      {"topic echo /chatter --count -1", "cairn: topic: --count expects an integer in [1, 1e+12], got '-1'"},
      {"topic echo /chatter --count 1e99", "cairn: topic: --count expects an integer in [1, 1e+12], got '1e99'"},
      {"topic echo /chatter --wait nan", "cairn: topic: --wait expects a number in [0, 3600], got 'nan'"},
      {"topic hz /chatter --duration nan", "cairn: topic: --duration expects a number in [0, 1e+09], got 'nan'"},
      {"topic hz /chatter --duration -1", "cairn: topic: --duration expects a number in [0, 1e+09], got '-1'"},
      {"topic list --wait -1", "cairn: topic: --wait expects a number in [0, 3600], got '-1'"},
      {"topic echo /chatter extra", "cairn: topic: unexpected argument 'extra' (topic echo <topic>) (see cairn --help)"},
      // each topic verb takes its own options only (echo --duration used to be accepted and ignored)
      {"topic echo /chatter --duration 5", "cairn: topic: unknown option '--duration' (see cairn --help)"},
      {"topic list --count 5", "cairn: topic: unknown option '--count' (see cairn --help)"},
      {"topic hz /chatter --once", "cairn: topic: unknown option '--once' (see cairn --help)"},
      {"topic list -t", "cairn: topic: unknown option '-t' (see cairn --help)"},
      {"param set /talker rate_hz 20 extra",
       "cairn: param: unexpected argument 'extra' (param set <node> <name> <value>; quote a value with spaces) (see "
       "cairn --help)"},
      {"param get /talker rate_hz --timeout 5x", "cairn: param: --timeout expects a number in [0, 3600], got '5x'"},
      {"param get /talker rate_hz --wait 0.5",
       "cairn: param: param has no discovery step: --timeout S bounds the wait for the reply (see cairn --help)"},
      {"component types extra", "cairn: component: unexpected argument 'extra' (component types) (see cairn --help)"},
      {"component unload /c 5x", "cairn: component: id expects an integer in [0, 9e+15], got '5x'"},
  };
  for (const auto& [args, err] : cases) {
    const auto r = run(kCairn + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(r.output, err + "\n") << args;
  }
  // --help after a built-in verb prints the usage (it was "unknown command", exit 2)
  for (const char* args : {"topic --help", "topic echo -h", "node --help", "component load --help", "param --help"}) {
    const auto r = run(kCairn + " " + args);
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("usage: cairn <command>", 0), 0u) << args << ": " << r.output;
  }
}

// `cairn bench ipc` runtime cases (numbers in docs/benchmarks.md; no timing is asserted here): every message the
// dispatch case sends arrives, the idle case's timer fires, a component loads and unloads, and a killed container
// is respawned and publishes again.
TEST(BenchIpc, RuntimeCasesRunAndLoseNothing) {
  auto field = [](const std::string& out, const std::string& key) {
    const auto p = out.find("\"" + key + "\":");
    return p == std::string::npos ? -1.0 : std::atof(out.c_str() + p + key.size() + 3);
  };
  auto r = run(kCairn + " bench ipc --quick --only dispatch 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(field(r.output, "sent"), 10000) << r.output;
  EXPECT_EQ(field(r.output, "callbacks"), field(r.output, "sent")) << r.output;
  EXPECT_EQ(field(r.output, "baseline_callbacks"), field(r.output, "baseline_sent")) << r.output;
  r = run(kCairn + " bench ipc --quick --only idle 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GE(field(r.output, "timer_expiries"), 15) << r.output;
  // Nothing due: the executor sleeps (no polling: a 10 ms poll would wake it 100 times a second, more often than
  // the 10 Hz timer it then gets). The measured figure is 0 (docs/benchmarks.md); the bound leaves room for stray
  // wake-ups on a loaded machine.
  EXPECT_LT(field(r.output, "wakeups"), field(r.output, "timer_expiries") / 2) << r.output;
  r = run(kCairn + " bench ipc --quick --only component_load 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("\"error\""), std::string::npos) << r.output;
  EXPECT_EQ(field(r.output, "loads"), 20) << r.output;  // --quick's iterations: every load succeeded
  EXPECT_GT(field(r.output, "p50_ms"), 0) << r.output;
  EXPECT_LE(field(r.output, "p50_ms"), field(r.output, "max_ms")) << r.output;
  r = run(kCairn + " bench ipc --quick --only respawn 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("\"error\""), std::string::npos) << r.output;
  EXPECT_EQ(field(r.output, "kills"), 3) << r.output;
  EXPECT_GT(field(r.output, "serving_again_p50_ms"), 0) << r.output;
  r = run(kCairn + " bench ipc --only bogus 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, "cairn: bench: --only: unknown case 'bogus'\n");
}
