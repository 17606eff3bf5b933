// cairn-bt: run, replay and watch behavior trees (the `cairn bt ...` verbs).
//   cairn-bt run <file.xml> [--tree ID] [--max-ticks N] [--period-ms P] [--trace] [--log FILE] [--no-wait]
//   cairn-bt replay <trace.log>             print a recorded trace in the --trace format
//   cairn-bt watch <trace.log> [--follow]   live tree view of a trace file being written (tmux-friendly)
//   cairn-bt model                          <TreeNodesModel> of the built-in nodes
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/trace.hpp"
#include "cairn/bt_executive/xml_loader.hpp"

using namespace cairn::bt;

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: cairn bt run <file.xml> [--tree ID] [--max-ticks N] [--period-ms P] [--trace] [--log FILE] "
               "[--no-wait]\n"
               "       cairn bt replay <trace.log>\n"
               "       cairn bt watch <trace.log> [--follow] [--interval-ms N]\n"
               "       cairn bt model\n");
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

bool parseInt(const char* s, long& out) {
  char* end = nullptr;
  out = std::strtol(s, &end, 10);
  return end && *end == '\0' && end != s;
}

int cmdRun(int argc, char** argv) {
  std::string file, tree_id, log_file;
  long max_ticks = 50, period_ms = 20;
  bool trace = false, wait = true;
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (a == "--tree") {
      const char* v = next();
      if (!v) return usage();
      tree_id = v;
    } else if (a == "--max-ticks" || a == "--period-ms") {
      const char* v = next();
      long x;
      if (!v || !parseInt(v, x) || x < 0) {
        std::fprintf(stderr, "cairn: %s needs a non-negative integer\n", a.c_str());
        return 2;
      }
      (a == "--max-ticks" ? max_ticks : period_ms) = x;
    } else if (a == "--trace") {
      trace = true;
    } else if (a == "--no-wait") {
      wait = false;
    } else if (a == "--log") {
      const char* v = next();
      if (!v) return usage();
      log_file = v;
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "cairn: unknown option %s\n", a.c_str());
      return 2;
    } else if (file.empty()) {
      file = a;
    } else {
      return usage();
    }
  }
  if (file.empty()) return usage();

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

int cmdReplay(int argc, char** argv) {
  if (argc != 1) return usage();
  std::ifstream is(argv[0]);
  if (!is) {
    std::fprintf(stderr, "cairn: %s: cannot open\n", argv[0]);
    return 2;
  }
  try {
    TraceReplay r = TraceReplay::read(is);
    for (const auto& t : r.transitions())
      std::printf("%s\n", formatTransition(t.step, r.paths()[t.uid], t.old_status, t.new_status).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: %s:%s\n", argv[0], e.what() + 4);
    return 2;
  }
  return 0;
}

int cmdWatch(int argc, char** argv) {
  std::string file;
  bool follow = false;
  long interval = 200;
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--follow") follow = true;
    else if (a == "--interval-ms" && i + 1 < argc && parseInt(argv[i + 1], interval)) ++i;
    else if (file.empty()) file = a;
    else return usage();
  }
  if (file.empty()) return usage();
  const bool tty = isatty(fileno(stdout));
  std::uintmax_t last_size = static_cast<std::uintmax_t>(-1);
  for (;;) {
    std::ifstream is(file);
    if (!is) {
      std::fprintf(stderr, "cairn: %s: cannot open\n", file.c_str());
      return 2;
    }
    std::string content((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
    if (content.size() != last_size) {
      last_size = content.size();
      // Ignore a partially written last line.
      if (!content.empty() && content.back() != '\n') content.erase(content.rfind('\n') + 1);
      std::istringstream ss(content);
      try {
        TraceReplay r = TraceReplay::read(ss);
        if (tty) std::printf("\033[H\033[2J");
        std::printf("%s  step %llu\n%s", file.c_str(), static_cast<unsigned long long>(r.lastStep()),
                    renderTree(r.paths(), r.statusesAfter(r.lastStep()), tty).c_str());
        std::fflush(stdout);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "cairn: %s:%s\n", file.c_str(), e.what() + 4);
        return 2;
      }
    }
    if (!follow) return 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(interval));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  std::string verb = argv[1];
  if (verb == "run") return cmdRun(argc - 2, argv + 2);
  if (verb == "replay") return cmdReplay(argc - 2, argv + 2);
  if (verb == "watch") return cmdWatch(argc - 2, argv + 2);
  if (verb == "model") {
    NodeFactory f;
    std::fputs(writeTreeNodesModel(f, true).c_str(), stdout);
    return 0;
  }
  return usage();
}
