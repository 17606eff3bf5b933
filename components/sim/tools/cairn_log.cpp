// cairn-log: CARMEN log playback from the command line (`cairn log <verb> ...`).
//   cairn-log info <file>                        counts, time span, beams per scan
//   cairn-log play <file> [--rate R] [--skip-malformed] [--limit N]
//       streams the records to stdout, one line each (`<stamp> scan <n> <frame>` / `<stamp> odom x y theta`),
//       paced at R times the log's speed (R = 0: as fast as possible, the default).
// Publishing /scan, /odom, TF and /clock over DDS is the player component's job (runtime adapter).
// Bad input: one line `cairn: <file>:<line>: <what>` on stderr and exit code 2.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <iostream>
#include <string>
#include <thread>

#include "cairn/sim/carmen.hpp"

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

int play(const std::string& path, CarmenReaderOptions opt, double rate, long limit) {
  CarmenReader reader(path, std::move(opt));
  CarmenRecord r;
  const auto wall0 = std::chrono::steady_clock::now();
  double log0 = NAN;
  long n = 0;
  while ((limit < 0 || n < limit) && reader.next(r)) {
    const double t = stampOf(r);
    if (std::isnan(log0)) log0 = t;
    if (rate > 0) std::this_thread::sleep_until(wall0 + std::chrono::duration<double>((t - log0) / rate));
    if (auto* l = std::get_if<CarmenLaser>(&r))
      std::printf("%.6f scan %zu %s %.3f %.3f %.4f\n", t, l->scan.ranges.size(), l->message.c_str(), l->robot_pose.x,
                  l->robot_pose.y, l->robot_pose.theta);
    else {
      const auto& o = std::get<CarmenOdom>(r);
      std::printf("%.6f odom %.4f %.4f %.4f %.3f %.3f\n", t, o.pose.x, o.pose.y, o.pose.theta, o.tv, o.rv);
    }
    ++n;
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || !std::strcmp(argv[1], "--help")) {
    std::cout << "usage: cairn-log info <file>\n"
                 "       cairn-log play <file> [--rate R] [--skip-malformed] [--limit N]\n"
                 "files: CARMEN logs (.clf, .log), plain, gzip or bzip2\n";
    return argc < 3 ? 2 : 0;
  }
  const std::string verb = argv[1], path = argv[2];
  CarmenReaderOptions opt;
  double rate = 0.0;
  long limit = -1;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--skip-malformed") {
      opt.skip_malformed = true;
      opt.on_warning = [](const InputError& e) { std::cerr << "cairn: warning: " << e.what() << " (skipped)\n"; };
    } else if (a == "--rate" && i + 1 < argc) {
      rate = std::atof(argv[++i]);
    } else if (a == "--limit" && i + 1 < argc) {
      limit = std::atol(argv[++i]);
    } else {
      usageError("unknown option '" + a + "'");
    }
  }
  try {
    if (verb == "info") return info(path, opt);
    if (verb == "play") return play(path, opt, rate, limit);
  } catch (const InputError& e) {
    std::cerr << "cairn: " << e.what() << "\n";
    return 2;
  }
  usageError("unknown verb '" + verb + "'");
}
