// cairn-bt: run, replay and watch behavior trees (the `cairn bt ...` verbs).
//   cairn-bt run <file.xml> [--tree ID] [--max-ticks N] [--period-ms P] [--trace] [--log FILE] [--no-wait]
//   cairn-bt replay <trace.log>             print a recorded trace in the --trace format
//   cairn-bt watch <trace.log> [--follow]   live tree view of a trace file being written (tmux-friendly)
//   cairn-bt watch --topic [NAME] [--count N | --once] [--timeout S]
//                                           live tree view of a running executive (its latched bt/status over DDS)
//   cairn-bt model                          <TreeNodesModel> of the built-in nodes
//   cairn-bt psbt-eval [--starts N] [--seed S] [--n-pl N] [--hotspots K] [--xml FILE]
//                                           model-based comparison of Stüde §5.4.4 on a synthetic 50 m x 25 m map
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/psbt.hpp"
#include "cairn/bt_executive/trace.hpp"
#include "cairn/bt_executive/xml_loader.hpp"
#include "cairn/strict_number.hpp"
#ifdef CAIRN_BT_WITH_RUNTIME
#include <condition_variable>
#include <deque>
#include <mutex>
#include <unistd.h>

#include "cairn/bt_executive/executive.hpp"
#include "cairn/node.hpp"
#include "cairn_bt_msgs/msg/TreeStatus.hpp"
#endif

using namespace cairn::bt;

namespace {

constexpr const char* kUsage =
    "usage: cairn bt run <file.xml> [--tree ID] [--max-ticks N] [--period-ms P] [--trace] [--log FILE] "
    "[--no-wait]\n"
    "       cairn bt replay <trace.log>\n"
    "       cairn bt watch <trace.log> [--follow] [--interval-ms N]\n"
    "       cairn bt watch --topic [NAME=/bt/status] [--count N | --once] [--timeout S (0-86400, 0: forever)]\n"
    "       cairn bt model\n"
    "       cairn bt psbt-eval [--starts 1-100000] [--seed S] [--n-pl 1-10] [--hotspots 0-1000] [--xml FILE]\n"
    "       cairn bt <verb> --help\n";

int usage() {
  std::fputs(kUsage, stderr);
  return 2;
}

/// The tree's clock for `run`: the scheduled time of the current step, (step-1)*period from 0, so traces do not
/// depend on scheduling jitter. Timers need no bookkeeping because the tree is ticked every period anyway.
class StepScheduler final : public Scheduler {
 public:
  TimePoint now() const override { return now_; }
  TimerId wakeUpAt(TimePoint) override { return ++id_; }
  void cancelTimer(TimerId) override {}
  void requestTick() override {}
  TimePoint now_{0};
  TimerId id_ = 0;
};

/// Bad command-line input: main() prints "cairn: <what>" (one line) and exits 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The value after the option argv[i] (advances i).
const char* optionValue(int argc, char** argv, int& i) {
  if (i + 1 >= argc) throw UsageError(std::string(argv[i]) + " needs a value");
  return argv[++i];
}

/// The integer after the option argv[i], which must lie in [lo, hi] (advances i).
long intOption(int argc, char** argv, int& i, long lo, long hi) {
  const std::string opt = argv[i];
  const std::string_view v = optionValue(argc, argv, i);
  const auto x = cairn::strict_number::parse_integer(v);
  if (!x || *x < lo || *x > hi)
    throw UsageError(opt + " needs an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" +
                     std::string(v) + "'");
  return static_cast<long>(*x);
}

/// The number (finite, decimal) after the option argv[i], which must lie in [lo, hi] (advances i).
double numberOption(int argc, char** argv, int& i, double lo, double hi) {
  const std::string opt = argv[i];
  const std::string_view v = optionValue(argc, argv, i);
  const auto x = cairn::strict_number::parse_finite(v);
  if (!x || *x < lo || *x > hi) {
    char range[64];
    std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
    throw UsageError(opt + " needs a number in " + range + ", got '" + std::string(v) + "'");
  }
  return *x;
}

/// The whole content of `file`; throws UsageError("FILE: ...") for a directory or a read error.
std::string readWholeFile(const std::string& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) throw UsageError(file + ": is a directory, not a trace file");
  std::ifstream is(file, std::ios::binary);
  if (!is) throw UsageError(file + ": cannot open");
  std::ostringstream ss;
  ss << is.rdbuf();
  if (is.bad()) throw UsageError(file + ": cannot read");
  return ss.str();
}

int cmdRun(int argc, char** argv) {
  std::string file, tree_id, log_file;
  long max_ticks = 50, period_ms = 20;
  bool trace = false, wait = true;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--tree") {
      tree_id = optionValue(argc, argv, i);
    } else if (a == "--max-ticks") {
      max_ticks = intOption(argc, argv, i, 0, 100'000'000);  // both bounds keep the step clock (ns) within int64
    } else if (a == "--period-ms") {
      period_ms = intOption(argc, argv, i, 0, 60'000);
    } else if (a == "--trace") {
      trace = true;
    } else if (a == "--no-wait") {
      wait = false;
    } else if (a == "--log") {
      log_file = optionValue(argc, argv, i);
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError("run: unknown option " + a);
    } else if (file.empty()) {
      file = a;
    } else {
      throw UsageError("run: one tree file only, got '" + file + "' and '" + a + "'");
    }
  }
  if (file.empty()) throw UsageError("run: missing the tree file (cairn bt run <file.xml>)");

  NodeFactory factory;
  Tree tree;
  try {
    LoadOptions opts;
    opts.main_tree = tree_id;
    tree = loadTreeFromFile(factory, file, opts);
  } catch (const LoadError& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: %s: %s\n", file.c_str(), e.what());
    return 2;
  }
  StepScheduler sched;
  tree.setScheduler(&sched);
  tree.context().setErrorHandler([](const RuntimeErrorEvent& e) {
    std::fprintf(stderr, "cairn: warning: %.*s: %s\n", int(e.path.size()), e.path.data(), e.message.c_str());
  });
  std::size_t obs = 0;
  bool have_obs = false;
  if (trace) {
    obs = tree.addObserver([](const TransitionEvent& e) {
      std::string l = formatTransition(e.step, e.path, e.old_status, e.new_status);
      l += '\n';
      std::fwrite(l.data(), 1, l.size(), stdout);
    });
    have_obs = true;
  }
  std::ofstream log_os;
  std::unique_ptr<FileLogger> logger;
  if (!log_file.empty()) {
    log_os.open(log_file);
    if (!log_os) {
      std::fprintf(stderr, "cairn: %s: cannot write\n", log_file.c_str());
      return 2;
    }
    logger = std::make_unique<FileLogger>(tree, log_os);
  }

  const auto wall0 = std::chrono::steady_clock::now();
  const auto period = std::chrono::milliseconds(period_ms);
  NodeStatus s = NodeStatus::IDLE;
  for (long step = 1; step <= max_ticks; ++step) {
    if (wait && step > 1) std::this_thread::sleep_until(wall0 + (step - 1) * period);  // absolute schedule
    sched.now_ = std::chrono::duration_cast<TimePoint>((step - 1) * period);
    s = tree.tickOnce();
    if (logger) logger->flush();
    if (s != NodeStatus::RUNNING) break;
  }
  std::fflush(stdout);
  if (have_obs) tree.removeObserver(obs);
  logger.reset();
  std::printf("RESULT %s\n", std::string(toString(s)).c_str());
  std::fflush(stdout);
  tree.setScheduler(nullptr);
  switch (s) {
    case NodeStatus::SUCCESS: return 0;
    case NodeStatus::FAILURE: return 1;
    default: return 3;  // still RUNNING after --max-ticks, or SKIPPED
  }
}

/// Parses the trace text of `file`; a malformed trace is a UsageError "FILE:LINE: ...".
TraceReplay parseTrace(const std::string& file, const std::string& text) {
  std::istringstream ss(text);
  try {
    return TraceReplay::read(ss);
  } catch (const std::runtime_error& e) {
    std::string m = e.what();  // "line N: ..."
    if (m.rfind("line ", 0) == 0) m.erase(0, 5);
    throw UsageError(file + ":" + m);
  }
}

int cmdReplay(int argc, char** argv) {
  if (argc != 1) throw UsageError("replay takes one trace file (cairn bt replay <trace.log>)");
  const std::string file = argv[0];
  const TraceReplay r = parseTrace(file, readWholeFile(file));
  for (const auto& t : r.transitions())
    std::printf("%s\n", formatTransition(t.step, r.paths()[t.uid], t.old_status, t.new_status).c_str());
  return 0;
}

#ifdef CAIRN_BT_WITH_RUNTIME
/// Remote watch: renders every TreeStatus heard on `topic` (latched: the current one at once, then one frame per
/// tick or command of the executive). Stops after `count` frames (0: until SIGINT); exit 1 if no frame arrives
/// within `timeout_s` (0: wait forever).
int watchTopic(const std::string& topic, long count, double timeout_s) {
  cairn::Executor exec;
  cairn::NodeOptions o("bt_watch_" + std::to_string(::getpid()), &exec);
  o.start_parameter_services = false;
  cairn::Node node(o);
  std::mutex mu;
  std::deque<cairn_bt_msgs::msg::TreeStatus> frames;
  std::shared_ptr<cairn::Subscription<cairn_bt_msgs::msg::TreeStatus>> sub;
  try {
    sub = node.create_subscription<cairn_bt_msgs::msg::TreeStatus>(
        topic, cairn::QoS::latched(), [&](const cairn_bt_msgs::msg::TreeStatus& s) {
          std::lock_guard l(mu);
          frames.push_back(s);
        });
  } catch (const std::exception& e) {  // a name DDS rejects ("bad topic!!")
    throw UsageError("watch --topic '" + topic + "': " + e.what());
  }
  cairn::Executor::install_signal_handlers();
  const bool tty = isatty(fileno(stdout));
  const auto wait = timeout_s > 0 ? std::chrono::nanoseconds(static_cast<std::int64_t>(timeout_s * 1e9))
                                  : std::chrono::nanoseconds(std::chrono::hours(24 * 365));
  for (long shown = 0; count <= 0 || shown < count;) {
    const bool got = exec.spin_until(
        [&] {
          std::lock_guard l(mu);
          return !frames.empty() || cairn::Executor::signal_received();
        },
        wait);
    if (cairn::Executor::signal_received()) return 0;
    if (!got) {
      std::fprintf(stderr, "cairn: %s: no tree status within %g s\n", node.resolve_name(topic).c_str(), timeout_s);
      return 1;
    }
    cairn_bt_msgs::msg::TreeStatus s;
    {
      std::lock_guard l(mu);
      s = std::move(frames.front());
      frames.pop_front();
    }
    try {
      const StatusSnapshot snap = parseStatusJson(s.status_json);
      if (tty) std::printf("\033[H\033[2J");
      std::printf("%s  tree %s  %s  step %llu\n%s", node.resolve_name(topic).c_str(), snap.tree.c_str(),
                  snap.state.c_str(), static_cast<unsigned long long>(snap.step),
                  renderTree(snap.paths, snap.statuses, tty).c_str());
      std::fflush(stdout);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "cairn: %s: bad status_json: %s\n", node.resolve_name(topic).c_str(), e.what());
      return 2;
    }
    ++shown;
  }
  return 0;
}
#endif

int cmdWatch(int argc, char** argv) {
  std::string file;
  bool follow = false;
  long interval = 200;
  if (argc >= 1 && std::strcmp(argv[0], "--topic") == 0) {
    std::string topic = "/bt/status";
    long count = 0;
    double timeout_s = 0;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--once") count = 1;
      else if (a == "--count") count = intOption(argc, argv, i, 1, std::numeric_limits<long>::max());
      else if (a == "--timeout") timeout_s = numberOption(argc, argv, i, 0, 86400);  // 0: wait forever
      else if (i == 1 && a.rfind("--", 0) != 0) topic = a;
      else if (a.rfind("--", 0) == 0) throw UsageError("watch --topic: unknown option " + a);
      else throw UsageError("watch --topic: unexpected argument '" + a + "' (the topic name goes right after --topic)");
    }
    if (topic.empty()) throw UsageError("watch --topic: empty topic name");
#ifdef CAIRN_BT_WITH_RUNTIME
    return watchTopic(topic, count, timeout_s);
#else
    std::fprintf(stderr, "cairn: bt watch --topic: cairn-bt was built without the runtime (cairn_executor)\n");
    return 2;
#endif
  }
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--follow") follow = true;
    else if (a == "--interval-ms") interval = intOption(argc, argv, i, 1, 3'600'000);
    else if (a.rfind("--", 0) == 0) throw UsageError("watch: unknown option " + a);
    else if (file.empty()) file = a;
    else throw UsageError("watch: one trace file only, got '" + file + "' and '" + a + "'");
  }
  if (file.empty()) throw UsageError("watch: missing the trace file (cairn bt watch <trace.log> or --topic)");
  const bool tty = isatty(fileno(stdout));
  std::uintmax_t last_size = static_cast<std::uintmax_t>(-1);
  for (;;) {
    std::string content = readWholeFile(file);
    if (content.size() != last_size) {
      last_size = content.size();
      // Ignore a partially written last line.
      if (!content.empty() && content.back() != '\n') content.erase(content.rfind('\n') + 1);
      if (!(follow && content.empty())) {  // a followed trace may not have its header yet
        const TraceReplay r = parseTrace(file, content);
        if (tty) std::printf("\033[H\033[2J");
        std::printf("%s  step %llu\n%s", file.c_str(), static_cast<unsigned long long>(r.lastStep()),
                    renderTree(r.paths(), r.statusesAfter(r.lastStep()), tty).c_str());
        std::fflush(stdout);
      }
    }
    if (!follow) return 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(interval));
  }
}

/// Stüde §5.4.4 model-based evaluation: random starts on a 50 m x 25 m, 1 m grid with synthetic hotspots,
/// r_D = 2 m, p'_s = 0.9, Δt = 1 s, l_fail = 100 m, v = 0.5 m/s, n_pl = 6, t_max = 200 s.
int cmdPsbtEval(int argc, char** argv) {
  long starts = 500, seed = 1, n_pl = 6, hotspots = 8;
  std::string xml_out;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--starts") starts = intOption(argc, argv, i, 1, 100'000);
    else if (a == "--seed") seed = intOption(argc, argv, i, 0, std::numeric_limits<long>::max());
    else if (a == "--n-pl") n_pl = intOption(argc, argv, i, 1, 10);  // 2·3^n candidate trees: ~6 s per start at 10
    else if (a == "--hotspots") hotspots = intOption(argc, argv, i, 0, 1000);
    else if (a == "--xml") xml_out = optionValue(argc, argv, i);
    else throw UsageError("psbt-eval: unknown argument '" + a + "'");
  }
  std::ofstream xml_os;
  if (!xml_out.empty()) {  // before the evaluation, which takes a while
    xml_os.open(xml_out);
    if (!xml_os) throw UsageError(xml_out + ": cannot write");
  }
  using namespace cairn::bt::psbt;
  Params p;
  p.n_pl = static_cast<int>(n_pl);
  const GridModel m = syntheticHotspots(50, 25, 1.0, static_cast<int>(hotspots), static_cast<std::uint64_t>(seed));
  std::vector<double> times;
  for (int k = 0; k <= 10; ++k) times.push_back(20.0 * k);
  const std::vector<std::string> methods = {"PSBT", "GM", "GC", "RND", "W", "PP"};
  std::vector<std::vector<double>> sum(methods.size(), std::vector<double>(times.size(), 0.0));
  std::vector<double> mu_inv(methods.size(), 0.0);
  std::vector<int> mu_n(methods.size(), 0);
  double plan_total = 0, plan_max = 0;
  std::size_t candidates = 0;
  std::mt19937_64 start_rng(static_cast<std::uint64_t>(seed) * 7919 + 1);
  std::uniform_int_distribution<int> ux(0, m.width() - 1), uy(0, m.height() - 1);
  for (long s = 0; s < starts; ++s) {
    const Eigen::Vector2d start = m.cellCenter(ux(start_rng), uy(start_rng));
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 1000003 + static_cast<std::uint64_t>(s));
    const auto t0 = std::chrono::steady_clock::now();
    const Synthesis syn = synthesize(m, start, p, rng);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    plan_total += dt;
    plan_max = std::max(plan_max, dt);
    candidates += syn.candidates;
    if (s == 0 && xml_os.is_open()) {
      xml_os << toXml(m, start, syn.best, p);
      xml_os.close();
      if (!xml_os) throw UsageError(xml_out + ": cannot write");
    }
    std::vector<Plan> plans{syn.best};
    for (auto b : {Baseline::GM, Baseline::GC, Baseline::RND, Baseline::W, Baseline::PP})
      plans.push_back(baseline(b, m, start, p, rng));
    for (std::size_t k = 0; k < plans.size(); ++k) {
      cairn::bt::sbt::Analysis a(plans[k].tree);
      auto pr = a.probabilities(times);
      for (std::size_t j = 0; j < times.size(); ++j) sum[k][j] += pr[j].first;
      if (a.successRate() > 0) {
        mu_inv[k] += 1.0 / a.successRate();
        ++mu_n[k];
      }
    }
  }
  std::printf("psbt-eval: %ld starts, 50 m x 25 m grid (1 m), %ld hotspots, seed %ld, n_pl %ld, r_D 2 m, p's 0.9, "
              "l_fail 100 m, v 0.5 m/s, t_max 200 s\n",
              starts, hotspots, seed, n_pl);
  std::printf("mean p_s,T(t)\n%-6s", "t [s]");
  for (std::size_t j = 1; j < times.size(); ++j) std::printf(" %6.0f", times[j]);
  std::printf("  mean 1/mu_T [s]\n");
  for (std::size_t k = 0; k < methods.size(); ++k) {
    std::printf("%-6s", methods[k].c_str());
    for (std::size_t j = 1; j < times.size(); ++j) std::printf(" %6.3f", sum[k][j] / double(std::max(1L, starts)));
    std::printf("  %8.1f\n", mu_n[k] ? mu_inv[k] / mu_n[k] : 0.0);
  }
  const std::size_t j140 = 7;
  const double psbt140 = sum[0][j140] / double(std::max(1L, starts)), gm140 = sum[1][j140] / double(std::max(1L, starts));
  std::printf("PSBT - GM at 140 s: %+.1f %% (points; thesis: +5.7 %%), relative %+.1f %%\n", 100 * (psbt140 - gm140),
              gm140 > 0 ? 100 * (psbt140 / gm140 - 1) : 0.0);
  std::printf("planning time per PSBT: mean %.3f s, max %.3f s, %.0f candidate trees each (thesis: 4.8 s, i7-7700T)\n",
              plan_total / double(std::max(1L, starts)), plan_max, double(candidates) / double(std::max(1L, starts)));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string verb = argv[1];
  const bool known = verb == "run" || verb == "replay" || verb == "watch" || verb == "psbt-eval" || verb == "model";
  if (known && argc > 2 && (std::strcmp(argv[2], "-h") == 0 || std::strcmp(argv[2], "--help") == 0)) {
    // `cairn bt replay --help` took "--help" for the trace file
    std::fputs(kUsage, stdout);
    return 0;
  }
  try {
    if (verb == "run") return cmdRun(argc - 2, argv + 2);
    if (verb == "replay") return cmdReplay(argc - 2, argv + 2);
    if (verb == "watch") return cmdWatch(argc - 2, argv + 2);
    if (verb == "psbt-eval") return cmdPsbtEval(argc - 2, argv + 2);
    if (verb == "model") {
      if (argc > 2) throw UsageError("model takes no arguments");
      NodeFactory f;
      std::fputs(writeTreeNodesModel(f, true).c_str(), stdout);
      return 0;
    }
    if (verb == "-h" || verb == "--help" || verb == "help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
  } catch (const UsageError& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // not the input: e.g. DDS unavailable
    std::fprintf(stderr, "cairn: %s: %s\n", verb.c_str(), e.what());
    return 1;
  }
  std::fprintf(stderr, "cairn: unknown verb '%s' (run, replay, watch, model, psbt-eval; see cairn bt --help)\n",
               verb.c_str());
  return 2;
}
