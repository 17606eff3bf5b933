// cairn-log: CARMEN log playback from the command line (`cairn log <verb> ...`).
//   cairn-log info <file>                        counts, time span, beams per scan
//   cairn-log play <file> [--rate R] [--pace time|consumers] [--skip-malformed] [--limit N]
//                  [--wait-subscribers N] [--loop] [-p name:=value]... [--print]
//       publishes scan, odom, /tf, /tf_static and /clock over DDS: the tool loads the cairn_sim::LogPlayer
//       component into an in-process container (one playback implementation) and exits when it is done.
//       R = 0 (the default): no wall-clock pacing; --pace consumers: each record only after every matched
//       reliable subscriber acknowledged the previous one. --print writes the records to stdout instead, one
//       line each (`<stamp> scan <n> <message> x y theta` / `<stamp> odom x y theta tv rv`), paced by R.
// Bad input: one line `cairn: <file>:<line>: <what>` on stderr and exit code 2.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <iostream>
#include <map>
#include <string>
#include <thread>

#include "cairn/sim/carmen.hpp"
#include "cairn/sim/log_playback.hpp"
#include "cairn/strict_number.hpp"
#ifdef CAIRN_LOG_HAVE_RUNTIME
#include <unistd.h>

#include <csignal>

#include "cairn/container.hpp"
#include "cairn/logging.hpp"
#include "cairn/parameters.hpp"
#include "log_player.hpp"
#endif

using namespace cairn::sim;

namespace {
[[noreturn]] void usageError(const std::string& msg) {
  std::cerr << "cairn: cairn-log: " << msg << "\n";
  std::exit(2);
}

int info(const std::string& path, CarmenReaderOptions opt) {
  CarmenReader reader(path, std::move(opt));
  CarmenRecord r;
  double t0 = NAN, t1 = NAN;
  std::size_t min_beams = SIZE_MAX, max_beams = 0;
  while (reader.next(r)) {
    const double t = stampOf(r);
    t0 = std::isnan(t0) ? t : std::min(t0, t);  // span from min to max: some logs are not time ordered
    t1 = std::isnan(t1) ? t : std::max(t1, t);
    if (auto* l = std::get_if<CarmenLaser>(&r)) {
      min_beams = std::min(min_beams, l->scan.ranges.size());
      max_beams = std::max(max_beams, l->scan.ranges.size());
    }
  }
  const auto& s = reader.stats();
  std::printf("%s: %zu lines, %zu scans (%zu..%zu beams), %zu odometry, %zu skipped, %zu malformed, %.1f s\n",
              path.c_str(), s.lines, s.lasers, s.lasers ? min_beams : 0, max_beams, s.odoms, s.skipped, s.malformed,
              std::isnan(t0) ? 0.0 : t1 - t0);
  return 0;
}

struct PlayOptions {
  double rate = 0.0;
  std::string pace = "time";
  long limit = -1;
  long wait_subscribers = 0;
  bool loop = false, print = false;
  std::map<std::string, std::string> params;  // -p name:=value
};

// --print: the records as text, paced at `rate` × the log's speed (0: as fast as possible).
int print(const std::string& path, CarmenReaderOptions opt, const PlayOptions& p) {
  LogPlaybackOptions lo;
  lo.reader = std::move(opt);
  lo.limit = p.limit > 0 ? static_cast<std::size_t>(p.limit) : 0;
  LogPlayback playback(path, std::move(lo));
  const auto wall0 = std::chrono::steady_clock::now();
  double log0 = NAN;
  while (const CarmenRecord* r = playback.peek()) {
    const double t = stampOf(*r);
    if (std::isnan(log0)) log0 = t;
    if (p.rate > 0) std::this_thread::sleep_until(wall0 + std::chrono::duration<double>((t - log0) / p.rate));
    if (auto* l = std::get_if<CarmenLaser>(r))
      std::printf("%.6f scan %zu %s %.3f %.3f %.4f\n", t, l->scan.ranges.size(), l->message.c_str(), l->robot_pose.x,
                  l->robot_pose.y, l->robot_pose.theta);
    else {
      const auto& o = std::get<CarmenOdom>(*r);
      std::printf("%.6f odom %.4f %.4f %.4f %.3f %.3f\n", t, o.pose.x, o.pose.y, o.pose.theta, o.tv, o.rv);
    }
    playback.pop();
  }
  return 0;
}

#ifdef CAIRN_LOG_HAVE_RUNTIME
std::atomic<bool> g_stop{false};

// Publishing: the LogPlayer component in an in-process container, spun on this thread until it is done.
int publish(const std::string& path, bool skip_malformed, const PlayOptions& p) {
  std::signal(SIGINT, [](int) { g_stop = true; });
  std::signal(SIGTERM, [](int) { g_stop = true; });
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "cairn_log_play_" + std::to_string(getpid()), loader);
  cairn::LoadRequest req{"cairn_sim::LogPlayer", "log_player"};
  req.parameters["file"] = path;
  req.parameters["rate"] = p.rate;
  req.parameters["pace"] = p.pace;
  req.parameters["skip_malformed"] = skip_malformed;
  req.parameters["limit"] = int64_t{std::max(0L, p.limit)};
  req.parameters["wait_for_subscribers"] = int64_t{p.wait_subscribers};
  req.parameters["loop"] = p.loop;
  for (const auto& [k, v] : p.params) req.parameters[k] = cairn::parse_parameter_text(v);
  // The container would log a failed load itself; the tool reports it once, as its one-line error.
  const cairn::Severity threshold = cairn::log_threshold();
  if (threshold < cairn::Severity::Fatal) cairn::set_log_threshold(cairn::Severity::Fatal);
  const auto loaded = mgr.load(req);
  cairn::set_log_threshold(threshold);
  if (!loaded.ok) {
    std::cerr << "cairn: " << loaded.error << "\n";
    return 2;
  }
  // (-p names the component does not declare are refused by the load itself, before anything plays.)
  const auto player = std::static_pointer_cast<cairn_sim::LogPlayer>(mgr.get(loaded.unique_id));
  while (!g_stop && !player->finished()) exec.spin_until([&] { return g_stop.load() || player->finished(); }, std::chrono::seconds(1));
  // Reliable subscribers get what was published before the process goes away.
  exec.spin_for(std::chrono::milliseconds(200));
  std::cerr << "cairn: log play: " << player->scansPublished() << " scans, " << player->odometryPublished()
            << " odometry records published\n";
  if (player->failed()) {
    std::cerr << "cairn: " << player->error() << "\n";
    return 2;
  }
  return 0;
}
#endif

int play(const std::string& path, CarmenReaderOptions opt, const PlayOptions& p) {
  if (p.print) return print(path, std::move(opt), p);
#ifdef CAIRN_LOG_HAVE_RUNTIME
  return publish(path, opt.skip_malformed, p);
#else
  usageError("play: built without the cairn runtime, only --print is available");
#endif
}

void usage() {
  std::cout << "usage: cairn-log info <file> [--skip-malformed]\n"
               "       cairn-log play <file> [--rate R] [--pace time|consumers] [--skip-malformed] [--limit N]\n"
               "                      [--wait-subscribers N] [--loop] [-p name:=value]... [--print]\n"
               "play publishes scan, odom, /tf, /tf_static and /clock (the cairn_sim::LogPlayer component, whose\n"
               "parameters -p sets); R = 0 (default): no wall-clock pacing; --pace consumers: each record after\n"
               "every reliable subscriber acknowledged the previous one; --print: text to stdout instead (with\n"
               "--rate, --limit and --skip-malformed only)\n"
               "files: CARMEN logs (.clf, .log), plain, gzip or bzip2\n";
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage();
    return argc < 2 ? 2 : 0;
  }
  const std::string verb = argv[1];
  if (verb != "info" && verb != "play") usageError("unknown verb '" + verb + "' (try --help)");
  if (argc < 3) usageError(verb + ": expected a log file");
  const std::string path = argv[2];
  CarmenReaderOptions opt;
  PlayOptions play_opts;
  std::string play_only, publish_only;  // first option given that only `play` / only publishing uses
  const auto value = [&](int& i, const std::string& a) -> std::string {
    if (i + 1 >= argc) usageError(a + " needs a value");
    return argv[++i];
  };
  const auto number = [&](const std::string& a, const std::string& v) {
    const auto x = cairn::strict_number::parse_finite(v);
    if (!x || *x < 0) usageError(a + ": '" + v + "' is not a number >= 0");
    return *x;
  };
  // ranges of the LogPlayer component's parameters
  const auto count = [&](const std::string& a, const std::string& v, double max) {
    const double x = number(a, v);
    if (x != std::floor(x) || x > max) {
      char range[64];
      std::snprintf(range, sizeof range, "[0, %.15g]", max);
      usageError(a + ": '" + v + "' is not an integer in " + range);
    }
    return static_cast<long>(x);
  };
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a != "--skip-malformed" && play_only.empty()) play_only = a;
    if (a == "--skip-malformed") {
      opt.skip_malformed = true;
      opt.on_warning = [](const InputError& e) { std::cerr << "cairn: warning: " << e.what() << " (skipped)\n"; };
    } else if (a == "--rate") {
      const std::string v = value(i, a);
      play_opts.rate = number(a, v);
      // 0 = no pacing; a tiny rate would wait practically forever for the second record
      if (play_opts.rate != 0.0 && !(play_opts.rate >= 0.001 && play_opts.rate <= 1000.0))
        usageError(a + ": '" + v + "' is not 0 (no pacing) or a number in [0.001, 1000]");
    } else if (a == "--limit") {
      play_opts.limit = count(a, value(i, a), 1e12);
    } else if (a == "--wait-subscribers") {
      play_opts.wait_subscribers = count(a, value(i, a), 1000);
      if (publish_only.empty()) publish_only = a;
    } else if (a == "--pace") {
      play_opts.pace = value(i, a);
      if (play_opts.pace != "time" && play_opts.pace != "consumers") usageError("--pace: '" + play_opts.pace + "' (time or consumers)");
      if (publish_only.empty()) publish_only = a;
    } else if (a == "--loop") {
      play_opts.loop = true;
      if (publish_only.empty()) publish_only = a;
    } else if (a == "--print") {
      play_opts.print = true;
    } else if (a == "-p") {
      const std::string kv = value(i, a);
      const auto eq = kv.find(":=");
      if (eq == std::string::npos || eq == 0) usageError("-p expects name:=value, got '" + kv + "'");
      play_opts.params[kv.substr(0, eq)] = kv.substr(eq + 2);
      if (publish_only.empty()) publish_only = a;
    } else {
      usageError("unknown option '" + a + "'");
    }
  }
  if (verb == "info" && !play_only.empty()) usageError("info: " + play_only + " is an option of play");
  if (play_opts.print && !publish_only.empty()) usageError("play: " + publish_only + " applies to publishing, not to --print");
  try {
    if (verb == "info") return info(path, opt);
    return play(path, opt, play_opts);
  } catch (const InputError& e) {
    std::cerr << "cairn: " << e.what() << "\n";
    return 2;
  }
}
