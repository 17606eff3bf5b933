// cairn-sim: command-line front end of the simulator core (`cairn sim <verb> ...`).
//   cairn-sim check <world>                      validate a world file, print a summary
//   cairn-sim bench [--world <name|file>]... [--json] [--seconds S] [--repeat N] [--seed N]
//   cairn-sim run --world <name|file> --duration <s> [--seed N] --out <dir> [...]
// Bad input: one line `cairn: <file>:<line>: <what>` on stderr, exit code 2.
#include <algorithm>
#include <climits>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/sim/laser.hpp"
#include "cairn/sim/people.hpp"
#include "cairn/sim/raycast.hpp"
#include "cairn/sim/rng.hpp"
#include "cairn/sim/simulator.hpp"
#include "cairn/sim/world.hpp"
#include "cairn/strict_number.hpp"

using namespace cairn::sim;

namespace {

[[noreturn]] void usageError(const std::string& msg) {
  std::cerr << "cairn: cairn-sim: " << msg << "\n";
  std::exit(2);
}

// Option values: a finite number, or an integer in [lo, hi]; anything else is a usage error naming verb and option.
double numberArg(const std::string& verb, const std::string& option, const std::string& v) {
  const auto d = cairn::strict_number::parse_finite(v);
  if (!d) usageError(verb + ": " + option + " expects a number, got '" + v + "'");
  return *d;
}

// A finite number in [lo, hi]; the range is in the message.
double numberArg(const std::string& verb, const std::string& option, const std::string& v, double lo, double hi) {
  const double d = numberArg(verb, option, v);
  if (d < lo || d > hi) {
    char range[64];
    std::snprintf(range, sizeof range, "[%.15g, %.15g]", lo, hi);
    usageError(verb + ": " + option + " expects a number in " + range + ", got '" + v + "'");
  }
  return d;
}

long long integerArg(const std::string& verb, const std::string& option, const std::string& v, long long lo,
                     long long hi) {
  const auto x = cairn::strict_number::parse_integer(v);
  if (!x || *x < lo || *x > hi)
    usageError(verb + ": " + option + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
               "], got '" + v + "'");
  return *x;
}
constexpr long long kMaxSeed = LLONG_MAX;
// `run` takes the Simulator component's parameter ranges (its seed: 0–9e15, a launch parameter is a double range).
constexpr long long kComponentMaxSeed = 9'000'000'000'000'000LL;
// Longest simulated span of `run` and `people` (about 3 years): keeps step and row counts far from overflow.
constexpr double kMaxDuration = 1e8;

void usage() {
  std::cout << "usage: cairn-sim <verb> [options]\n"
               "  check <world>                 validate a world (name or YAML file) and print a summary\n"
               "  bench [--world W]... [--json] [--seconds S] [--repeat N] [--seed N]\n"
               "                                ray-casting throughput (720-beam scans/s) vs a naive baseline\n"
               "  run --world W --duration S [--seed 1] --out DIR [--route NAME|none] [--no-people] [--no-crowd]\n"
               "      [--realtime-factor F] [--route-speed V] [--dwell S] [--fov-deg D] [--resolution-deg D]\n"
               "      [--laser-rate HZ] [--range-max M]\n"
               "                                headless run; writes robot_path.csv, people.csv, scan_digest.txt\n"
               "  people --world W --duration S --out FILE [--rate HZ] [--seed N]\n"
               "                                people only (no robot): t,id,x,y at HZ (default 1), fast for weeks\n";
}

// Uniform random free positions inside the world's regions, at least `clearance` from any wall.
std::vector<Pose2> samplePoses(const World& w, const SegmentGrid& grid, int n, Rng& rng, double clearance) {
  std::vector<Pose2> out;
  if (w.regions.empty()) usageError(w.file + ": world has no regions to sample poses in");
  int guard = 0;
  while (static_cast<int>(out.size()) < n && ++guard < 1000000) {
    const Region& r = w.regions[static_cast<std::size_t>(rng.uniform() * w.regions.size())];
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (const auto& p : r.polygon) x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    const Vec2 p{rng.uniform(x0, x1), rng.uniform(y0, y1)};
    if (!r.contains(p) || grid.distanceToNearest(p, clearance) < clearance) continue;
    out.push_back({p.x, p.y, rng.uniform(-std::numbers::pi, std::numbers::pi)});
  }
  return out;
}

struct BenchResult {
  std::string world;
  int beams = 0;
  std::size_t static_segments = 0, dynamic_segments = 0, circles = 0;
  double cell_size = 0;
  double scans_per_s = 0, ideal_scans_per_s = 0, naive_scans_per_s = 0, wall_scans_per_s = 0;
  double mean_range = 0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Seconds of CPU time consumed by this thread: "scans per second on one core" stays meaningful on a
// shared, loaded machine, where wall-clock rates depend on what else runs.
double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Rate {
  double cpu = 0;   // calls per CPU second
  double wall = 0;  // calls per wall-clock second
};

template <class F>
Rate rate(double seconds, F&& one) {  // calls one() until `seconds` of CPU time have passed
  using clock = std::chrono::steady_clock;
  const auto w0 = clock::now();
  const double c0 = threadCpuSeconds();
  long calls = 0;
  double elapsed = 0;
  do {
    for (int k = 0; k < 16; ++k) one();
    calls += 16;
    elapsed = threadCpuSeconds() - c0;
  } while (elapsed < seconds);
  const double wall = std::chrono::duration<double>(clock::now() - w0).count();
  return {static_cast<double>(calls) / elapsed, static_cast<double>(calls) / wall};
}

BenchResult benchWorld(const std::string& name, double seconds, int repeat, std::uint64_t seed) {
  const World w = loadWorld(resolveWorldPath(name));
  const SegmentGrid grid(w.walls);
  LaserConfig cfg;  // defaults: 360°, 0.5° -> 720 beams, 20 m
  const LaserSimulator laser(cfg, grid);
  Rng rng(seed);
  const auto poses = samplePoses(w, grid, 256, rng, 0.35);
  // furnished world at t = 0 plus 10 people (20 leg circles) at random free spots
  std::vector<Segment> dyn;
  std::vector<Circle> circles;
  w.dynamicGeometry(0.0, dyn, circles);
  const auto people = samplePoses(w, grid, 10, rng, 0.35);
  for (const auto& p : people) {
    const Vec2 side{-std::sin(p.theta) * 0.1, std::cos(p.theta) * 0.1};
    circles.push_back({Vec2{p.x, p.y} + side, 0.06, 0.3F});
    circles.push_back({Vec2{p.x, p.y} - side, 0.06, 0.3F});
  }
  std::vector<Segment> all = w.walls;
  all.insert(all.end(), dyn.begin(), dyn.end());

  BenchResult r;
  r.world = w.name;
  r.beams = cfg.beams();
  r.static_segments = w.walls.size();
  r.dynamic_segments = dyn.size();
  r.circles = circles.size();
  r.cell_size = grid.cellSize();

  std::vector<RayHit> hits;
  double sum_range = 0;
  std::size_t n_range = 0;
  for (const auto& p : poses) {
    laser.castIdeal(compose(p, cfg.mount), dyn, circles, hits);
    for (const auto& h : hits) if (h.hit) sum_range += h.range, ++n_range;
  }
  r.mean_range = n_range ? sum_range / n_range : 0;

  // Naive baseline: every beam against every segment (static + dynamic) and every circle.
  const int nb = cfg.beams();
  std::vector<double> bc(nb), bs(nb);
  for (int i = 0; i < nb; ++i) bc[i] = std::cos(cfg.angleMin() + i * cfg.resolution), bs[i] = std::sin(cfg.angleMin() + i * cfg.resolution);
  volatile double sink = 0;
  std::vector<double> full, ideal, naive, full_wall;
  Rate rt;
  for (int rep = 0; rep < repeat; ++rep) {
    std::size_t k = 0;
    LaserScan scan;
    rt = rate(seconds, [&] {
      laser.scan(poses[k++ % poses.size()], 0.0, dyn, circles, rng, scan);
      sink = sink + scan.ranges[0];
    });
    full.push_back(rt.cpu);
    full_wall.push_back(rt.wall);
    ideal.push_back(rate(seconds, [&] {
      laser.castIdeal(compose(poses[k++ % poses.size()], cfg.mount), dyn, circles, hits);
      sink = sink + hits[0].range;
    }).cpu);
    naive.push_back(rate(seconds, [&] {
      const Pose2 lp = compose(poses[k++ % poses.size()], cfg.mount);
      const double c = std::cos(lp.theta), s = std::sin(lp.theta);
      double acc = 0;
      for (int i = 0; i < nb; ++i) {
        const Vec2 d{c * bc[i] - s * bs[i], s * bc[i] + c * bs[i]};
        RayHit h = castNaive(all, {lp.x, lp.y}, d, cfg.range_max);
        for (const auto& ci : circles) {
          const double t = rayCircle({lp.x, lp.y}, d, ci.center, ci.radius);
          if (t >= 0 && t < h.range) h.range = t;
        }
        acc += h.range;
      }
      sink = sink + acc;
    }).cpu);
  }
  r.scans_per_s = median(full);
  r.ideal_scans_per_s = median(ideal);
  r.naive_scans_per_s = median(naive);
  r.wall_scans_per_s = median(full_wall);
  return r;
}

std::string jsonResult(const BenchResult& r) {
  std::ostringstream o;
  o.precision(6);
  o << "{\"world\": \"" << r.world << "\", \"beams\": " << r.beams << ", \"scans_per_s\": " << std::round(r.scans_per_s)
    << ", \"wall_scans_per_s\": " << std::round(r.wall_scans_per_s)
    << ", \"ideal_scans_per_s\": " << std::round(r.ideal_scans_per_s)
    << ", \"baseline_naive_scans_per_s\": " << std::round(r.naive_scans_per_s)
    << ", \"speedup_vs_naive\": " << r.ideal_scans_per_s / r.naive_scans_per_s
    << ", \"static_segments\": " << r.static_segments << ", \"dynamic_segments\": " << r.dynamic_segments
    << ", \"circles\": " << r.circles << ", \"grid_cell_m\": " << r.cell_size << ", \"mean_hit_range_m\": " << r.mean_range
    << "}";
  return o.str();
}

int cmdBench(int argc, char** argv) {
  std::vector<std::string> worlds;
  bool json = false;
  double seconds = 0.5;
  int repeat = 3;
  std::uint64_t seed = 1;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usageError("bench: " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--world") worlds.push_back(value());
    else if (a == "--json") json = true;
    else if (a == "--seconds") seconds = numberArg("bench", a, value(), 0.001, 3600.0);
    else if (a == "--repeat") repeat = static_cast<int>(integerArg("bench", a, value(), 1, 1000000));
    else if (a == "--seed") seed = static_cast<std::uint64_t>(integerArg("bench", a, value(), 0, kMaxSeed));
    else usageError("bench: unknown option '" + a + "'");
  }
  if (worlds.empty() || (worlds.size() == 1 && worlds[0] == "all")) worlds = shippedWorlds();
  std::vector<BenchResult> results;
  for (const auto& w : worlds) results.push_back(benchWorld(w, seconds, repeat, seed));
  if (json) {
    // One JSON object: the first world's figures at top level, every world under "worlds".
    const BenchResult& f = results.front();
    std::cout << "{\"world\": \"" << f.world << "\", \"beams\": " << f.beams << ", \"scans_per_s\": " << std::round(f.scans_per_s)
              << ", \"baseline_naive_scans_per_s\": " << std::round(f.naive_scans_per_s) << ", \"repeat\": " << repeat
              << ", \"cpu_seconds_per_run\": " << seconds << ", \"timing\": \"thread CPU time\", \"worlds\": {";
    for (std::size_t i = 0; i < results.size(); ++i)
      std::cout << (i ? ", " : "") << "\"" << results[i].world << "\": " << jsonResult(results[i]);
    std::cout << "}}\n";
  } else {
    for (const auto& r : results)
      std::printf("%-10s %4d beams  %9.0f scans/s (noise incl.)  %9.0f ideal  naive baseline %8.0f  x%.1f\n",
                  r.world.c_str(), r.beams, r.scans_per_s, r.ideal_scans_per_s, r.naive_scans_per_s,
                  r.ideal_scans_per_s / r.naive_scans_per_s);
  }
  return 0;
}


int cmdRun(int argc, char** argv) {
  std::string world_name, out_dir, route_name;
  double duration = -1, rtf = 0;
  RouteConfig rc;
  rc.loop = true;
  SimConfig cfg;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usageError("run: " + a + " needs a value");
      return argv[++i];
    };
    // ranges as the Simulator component's parameters (README), so that a run can be repeated in a launch
    auto number = [&](double lo, double hi) { return numberArg("run", a, value(), lo, hi); };
    if (a == "--world") world_name = value();
    else if (a == "--duration") duration = number(0.0, kMaxDuration);
    else if (a == "--seed") cfg.seed = static_cast<std::uint64_t>(integerArg("run", a, value(), 0, kComponentMaxSeed));
    else if (a == "--out") out_dir = value();
    else if (a == "--route") route_name = value();
    else if (a == "--no-people") cfg.people = false;
    else if (a == "--no-crowd") cfg.crowd = false;
    else if (a == "--realtime-factor") {
      const std::string v = value();
      rtf = numberArg("run", a, v);
      if (rtf != 0.0 && !(rtf >= 0.01 && rtf <= 1000.0))
        usageError("run: --realtime-factor expects 0 (as fast as possible) or a number in [0.01, 1000], got '" + v + "'");
    }
    else if (a == "--route-speed") rc.speed = number(0.01, 5.0);
    else if (a == "--dwell") rc.dwell = number(0.0, 3600.0);
    else if (a == "--fov-deg") cfg.laser.fov = number(1.0, 360.0) * std::numbers::pi / 180.0;
    else if (a == "--resolution-deg") cfg.laser.resolution = number(0.05, 10.0) * std::numbers::pi / 180.0;
    else if (a == "--laser-rate") cfg.laser.rate = number(0.1, 200.0);
    else if (a == "--range-max") cfg.laser.range_max = number(0.1, 200.0);
    else usageError("run: unknown option '" + a + "'");
  }
  if (world_name.empty() || duration < 0 || out_dir.empty()) usageError("run: --world, --duration and --out are required");
  if (cfg.laser.resolution > cfg.laser.fov) usageError("run: --resolution-deg must not exceed --fov-deg");
  // The simulator scans at most once per physics step: above 100 Hz the step is one laser period.
  if (cfg.laser.rate * cfg.physics_dt > 1.0) cfg.physics_dt = 1.0 / cfg.laser.rate;
  World world = loadWorld(resolveWorldPath(world_name));
  std::optional<std::vector<Vec2>> route;
  if (route_name.empty() && !world.routes.empty()) route_name = world.routes.begin()->first;
  if (!route_name.empty() && route_name != "none") {
    const auto it = world.routes.find(route_name);
    if (it == world.routes.end()) usageError("run: world '" + world.name + "' has no route '" + route_name + "'");
    route = it->second;
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) usageError("run: --out '" + out_dir + "': " + ec.message());
  Simulator sim(std::move(world), cfg);
  if (route) sim.followRoute(*route, rc);
  std::ofstream path_csv(out_dir + "/robot_path.csv"), people_csv(out_dir + "/people.csv");
  if (!path_csv || !people_csv) usageError("run: --out '" + out_dir + "': cannot write files there");
  path_csv << "t,x,y,theta,odom_x,odom_y,odom_theta\n";
  people_csv << "t,id,x,y\n";
  char buf[256];
  std::uint64_t digest = 0xcbf29ce484222325ULL;
  long scans = 0;
  // One chunk per laser period (at least one physics step). The run ends at the physics step nearest to
  // `duration`, as Simulator::advance rounds: a remainder under half a step is not simulated (and cannot stall).
  const double dt = cfg.physics_dt;
  const double chunk = 1.0 / cfg.laser.rate;
  const long end_step = std::lround(duration / dt);
  const auto wall0 = std::chrono::steady_clock::now();
  SimOutput out;
  while (std::lround(sim.time() / dt) < end_step) {
    out.scans.clear();
    out.odometry.clear();
    out.ground_truth.clear();
    sim.advance(std::min(chunk, duration - sim.time()), out);
    for (const auto& s : out.scans) digest = scanDigest(s, digest), ++scans;
    for (std::size_t i = 0; i < out.odometry.size(); ++i) {
      const auto& g = out.ground_truth[i].pose;
      const auto& o = out.odometry[i].pose;
      std::snprintf(buf, sizeof buf, "%.3f,%.4f,%.4f,%.5f,%.4f,%.4f,%.5f\n", out.odometry[i].stamp, g.x, g.y, g.theta, o.x,
                    o.y, o.theta);
      path_csv << buf;
    }
    for (const auto& p : sim.people()) {
      std::snprintf(buf, sizeof buf, "%.3f,%d,%.4f,%.4f\n", sim.time(), p.id, p.position.x, p.position.y);
      people_csv << buf;
    }
    if (rtf > 0) std::this_thread::sleep_until(wall0 + std::chrono::duration<double>(sim.time() / rtf));
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::ofstream dig(out_dir + "/scan_digest.txt");
  std::snprintf(buf, sizeof buf, "scans %ld\nfnv1a64 %016llx\n", scans, static_cast<unsigned long long>(digest));
  dig << buf;
  std::printf("{\"world\": \"%s\", \"seed\": %llu, \"sim_seconds\": %.3f, \"scans\": %ld, \"scan_digest\": \"%016llx\", "
              "\"wall_seconds\": %.3f, \"realtime_factor\": %.1f}\n",
              sim.world().name.c_str(), static_cast<unsigned long long>(cfg.seed), sim.time(), scans,
              static_cast<unsigned long long>(digest), wall, wall > 0 ? sim.time() / wall : 0.0);
  return 0;
}

// People only (no robot, no laser): fast generation of long crowd/trajectory ground truth, e.g. weeks of
// people positions for CoPA-Map training data.
int cmdPeople(int argc, char** argv) {
  std::string world_name, out_file;
  double duration = -1, rate = 1.0;
  std::uint64_t seed = 1;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usageError("people: " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--world") world_name = value();
    else if (a == "--duration") duration = numberArg("people", a, value(), 0.0, kMaxDuration);
    else if (a == "--rate") rate = numberArg("people", a, value(), 1e-4, 1000.0);
    else if (a == "--seed") seed = static_cast<std::uint64_t>(integerArg("people", a, value(), 0, kMaxSeed));
    else if (a == "--out") out_file = value();
    else usageError("people: unknown option '" + a + "'");
  }
  if (world_name.empty() || duration < 0 || out_file.empty()) usageError("people: --world, --duration and --out are required");
  const World world = loadWorld(resolveWorldPath(world_name));
  // Same stream as the full simulator's people (Simulator forks stream 3 from the seed).
  PeopleSimulator people(world, GaitConfig{}, Rng(seed).fork(3));
  std::ofstream out(out_file);
  if (!out) usageError("people: --out '" + out_file + "': cannot write it");
  out << "t,id,x,y\n";
  char buf[128];
  const long steps = std::lround(duration * rate);
  std::size_t rows = 0;
  for (long k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / rate;
    people.update(t);
    for (const auto& p : people.people()) {
      std::snprintf(buf, sizeof buf, "%.3f,%d,%.4f,%.4f\n", t, p.id, p.position.x, p.position.y);
      out << buf;
      ++rows;
    }
  }
  std::printf("{\"world\": \"%s\", \"seed\": %llu, \"sim_seconds\": %.1f, \"rows\": %zu, \"crowd_spawned\": %d}\n",
              world.name.c_str(), static_cast<unsigned long long>(seed), duration, rows, people.spawnedCrowd());
  return 0;
}

int cmdCheck(int argc, char** argv) {
  if (argc != 1) usageError("check: expected one world name or file");
  const World w = loadWorld(resolveWorldPath(argv[0]));
  // recorded people files are read as `run` reads them, so that a malformed one fails here too
  for (const auto& src : w.people)
    if (!src.file.empty()) loadPeopleSource(src);
  std::printf("%s: %zu wall segments, %zu regions, %zu doors, %zu furniture, %zu markers, %zu routes, bounds "
              "[%.2f, %.2f] x [%.2f, %.2f]\n",
              w.name.c_str(), w.walls.size(), w.regions.size(), w.doors.size(), w.furniture.size(), w.markers.size(),
              w.routes.size(), w.bounds_min.x, w.bounds_max.x, w.bounds_min.y, w.bounds_max.y);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage();
    return argc < 2 ? 2 : 0;
  }
  const std::string verb = argv[1];
  try {
    if (verb == "bench") return cmdBench(argc - 2, argv + 2);
    if (verb == "check") return cmdCheck(argc - 2, argv + 2);
    if (verb == "run") return cmdRun(argc - 2, argv + 2);
    if (verb == "people") return cmdPeople(argc - 2, argv + 2);
  } catch (const InputError& e) {
    std::cerr << "cairn: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "cairn: cairn-sim " << verb << ": " << e.what() << "\n";
    return 2;
  }
  usageError("unknown verb '" + verb + "' (try --help)");
}
