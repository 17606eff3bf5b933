// `cairn slam run` (offline SLAM on a CARMEN log) and `cairn slam eval` (Kümmerle et al. 2009 relations metric).
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "cairn/graph_slam/g2o_io.hpp"
#include "cairn/graph_slam/occupancy_grid.hpp"
#include "cairn/graph_slam/relations.hpp"
#include "cairn/graph_slam/slam.hpp"
#include "cairn/graph_slam/slam_params.hpp"
#include "cairn/sim/carmen.hpp"
#include "cairn/sim/world.hpp"  // InputError
#include "cli_util.hpp"
#include "verbs.hpp"

namespace gs = cairn::graph_slam;
using cairn::slam_cli::JsonObject;

namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

int fail(const std::string& what) {
  std::cerr << "cairn: slam: " << what << "\n";
  return 2;
}

void relationsJson(JsonObject& j, const gs::RelationsResult& r) {
  j.integer("relations", static_cast<long long>(r.relations))
      .integer("used", static_cast<long long>(r.used))
      .integer("missing", static_cast<long long>(r.missing))
      .num("trans_mean_m", r.trans_mean)
      .num("trans_std_m", r.trans_std)
      .num("trans_max_m", r.trans_max)
      .num("rot_mean_deg", r.rot_mean * kRadToDeg)
      .num("rot_std_deg", r.rot_std * kRadToDeg)
      .num("rot_max_deg", r.rot_max * kRadToDeg);
}

void printRelations(const char* what, const gs::RelationsResult& r) {
  std::printf("%srelations: %zu used of %zu\n", what, r.used, r.relations);
  std::printf("%stranslational error: %.4f +- %.4f m (max %.4f)\n", what, r.trans_mean, r.trans_std, r.trans_max);
  std::printf("%srotational error:    %.3f +- %.3f deg (max %.3f)\n", what, r.rot_mean * kRadToDeg,
              r.rot_std * kRadToDeg, r.rot_max * kRadToDeg);
}

}  // namespace

int slamEvalVerb(const std::vector<std::string>& args) {
  std::string relations_path, poses_path, odometry_log, corrected_log, raw_log;
  bool json = false;
  bool allow_missing = false;
  gs::RelationsOptions opt;
  try {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw std::invalid_argument(a + " needs a value");
        return args[++i];
      };
      if (a == "--relations") relations_path = value();
      else if (a == "--poses") poses_path = value();
      else if (a == "--json") json = true;
      else if (a == "--allow-missing") allow_missing = true;
      else if (a == "--stamp-tolerance") {
        opt.stamp_tolerance = cairn::slam_cli::parseDouble(value(), "--stamp-tolerance");
        if (opt.stamp_tolerance < 0) throw std::invalid_argument("--stamp-tolerance must be >= 0 s");
      } else if (a == "--odometry-baseline")
        odometry_log = value();
      else if (a == "--corrected") corrected_log = value();
      else if (a == "--carmen") raw_log = value();
      else throw std::invalid_argument("eval: unknown option '" + a + "'");
    }
    if (poses_path.empty()) throw std::invalid_argument("eval needs --poses");
    if (relations_path.empty() && corrected_log.empty())
      throw std::invalid_argument("eval needs --relations and/or --corrected <log> --carmen <raw log>");
    if (!corrected_log.empty() && raw_log.empty()) throw std::invalid_argument("--corrected needs --carmen <raw log>");
    if (!odometry_log.empty() && relations_path.empty())  // it scores the log's odometry on the relations
      throw std::invalid_argument("--odometry-baseline needs --relations");
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  try {
    const auto poses = gs::readPoses(poses_path);
    JsonObject j;
    if (!relations_path.empty()) {
      const auto relations = gs::readRelations(relations_path);
      const gs::RelationsResult r = gs::evaluateRelations(relations, poses, opt);
      if (r.missing > 0 && !allow_missing)
        return fail(relations_path + ":" + std::to_string(r.first_missing_line) + ": " + std::to_string(r.missing) +
                    " of " + std::to_string(r.relations) + " relations have a stamp without a pose in " + poses_path +
                    " (--allow-missing skips them)");
      if (r.used == 0) return fail(relations_path + ": no relation could be evaluated");
      relationsJson(j, r);
      if (!json) printRelations("", r);
      if (!odometry_log.empty()) {
        // Same-run baseline: the log's raw odometry scored on the same relations.
        const gs::RelationsResult o = gs::evaluateRelations(relations, gs::odometryTrajectory(odometry_log), opt);
        JsonObject oj;
        relationsJson(oj, o);
        j.raw("odometry_baseline", oj.text());
        if (!json) printRelations("odometry baseline ", o);
      }
    }
    if (!corrected_log.empty()) {
      const gs::TrajectoryAgreement a = gs::compareWithCorrectedLog(corrected_log, raw_log, poses, opt.stamp_tolerance);
      if (a.matched < 2) return fail(corrected_log + ": fewer than 2 of its scans were found in " + raw_log + " and " + poses_path);
      JsonObject cj;
      cj.integer("corrected_scans", static_cast<long long>(a.corrected_scans))
          .integer("matched", static_cast<long long>(a.matched))
          .num("ate_rmse_m", a.ate_rmse)
          .num("ate_max_m", a.ate_max)
          .num("heading_rmse_deg", a.heading_rmse * kRadToDeg);
      j.raw("corrected_log", cj.text());
      if (!json)
        std::printf("corrected log: %zu of %zu scans matched, ATE %.3f m RMSE (max %.3f), heading %.2f deg RMSE\n",
                    a.matched, a.corrected_scans, a.ate_rmse, a.ate_max, a.heading_rmse * kRadToDeg);
    }
    if (json) std::cout << j.text() << "\n";
    return 0;
  } catch (const cairn::sim::InputError& e) {
    return fail(e.what());
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}

namespace {

// Applies a flat `key: value` YAML config (keys of slamParameters()); errors name file:line and the key.
// Applies a --config file; returns the keys it set.
std::vector<std::string> applyConfig(const std::string& path, gs::SlamOptions& options) {
  YAML::Node root;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw cairn::sim::InputError(path, 0, "cannot open file: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw cairn::sim::InputError(path, 0, "cannot open file");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Binary garbage is not YAML; yaml-cpp would quote the bytes (newlines included) in its message.
  int line = 1;
  for (const char c : text) {
    const auto b = static_cast<unsigned char>(c);
    if (b == '\n') ++line;
    if ((b < 0x20 && b != '\n' && b != '\r' && b != '\t') || b == 0x7f) {
      char what[64];
      std::snprintf(what, sizeof what, "not a text file (control byte 0x%02x)", b);
      throw cairn::sim::InputError(path, line, what);
    }
  }
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw cairn::sim::InputError(path, e.mark.line + 1, e.msg);
  }
  std::vector<std::string> keys;
  if (root.IsNull()) return keys;
  if (!root.IsMap()) throw cairn::sim::InputError(path, root.Mark().line + 1, "expected a map of SLAM parameters");
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (!kv.second.IsScalar())
      throw cairn::sim::InputError(path, kv.second.Mark().line + 1, key + ": expected a scalar value");
    try {
      gs::setSlamParameter(options, key, kv.second.Scalar());
    } catch (const std::invalid_argument& e) {
      throw cairn::sim::InputError(path, kv.first.Mark().line + 1, e.what());
    }
    keys.push_back(key);
  }
  return keys;
}

struct LogScan {
  std::size_t lasers = 0;
  std::optional<gs::Pose2> mount;  ///< laser in base frame from the first FLASER with poses
  std::size_t backwards = 0;       ///< scans (within the limit) stamped before an earlier scan
  std::size_t first_backwards_line = 0;
};

// First pass over the log: the scan count (progress/ETA), the laser mount, and scans whose timestamp goes
// backwards (counted over the scans the run will use: `limit`, -1 all). GraphSlam::addScan rejects such
// scans; real logs have them (radish intel.clf: 217 of its first 1500), so they are reported, not fatal.
// FLASER carries the laser pose and the robot's odometry pose; their difference is the mount (FR079: 4 cm
// forward). Ignored if implausible.
LogScan scanLog(const std::string& log, const cairn::sim::CarmenReaderOptions& opt, long limit) {
  cairn::sim::CarmenReader reader(log, opt);
  cairn::sim::CarmenRecord rec;
  LogScan out;
  double previous = -std::numeric_limits<double>::infinity();
  while (reader.next(rec)) {
    const auto* laser = std::get_if<cairn::sim::CarmenLaser>(&rec);
    if (laser == nullptr) continue;
    if (limit < 0 || static_cast<long>(out.lasers) < limit) {
      if (laser->scan.stamp < previous && out.backwards++ == 0)
        out.first_backwards_line = reader.lineNumber();
      previous = std::max(previous, laser->scan.stamp);
    }
    if (out.lasers++ == 0 && laser->has_pose) {
      const gs::Pose2 robot{{laser->robot_pose.x, laser->robot_pose.y}, laser->robot_pose.theta};
      const gs::Pose2 las{{laser->laser_pose.x, laser->laser_pose.y}, laser->laser_pose.theta};
      const gs::Pose2 mount = gs::compose(gs::inverse(robot), las);
      if (mount.t.norm() < 1.0 && std::abs(mount.theta) < 0.1) out.mount = mount;
    }
  }
  return out;
}

void progress(std::size_t done, std::size_t total, double elapsed) {
  const double f = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
  const int width = 30;
  const int filled = static_cast<int>(f * width);
  const double eta = f > 0 ? elapsed * (1.0 - f) / f : 0.0;
  std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  %zu/%zu scans  %.0f s elapsed, ETA %.0f s ", filled,
               "##############################", width - filled, "", 100.0 * f, done, total, elapsed, eta);
  std::fflush(stderr);
}

}  // namespace

int slamRunVerb(const std::vector<std::string>& args) {
  std::string log, out_dir, config, load_path;
  bool json = false, quiet = false, skip_malformed = false;
  long limit = -1;
  std::string laser_mount = "auto";
  bool mount_given = false;
  gs::SlamOptions options;
  try {
    std::vector<std::pair<std::string, std::string>> sets;
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size()) throw std::invalid_argument(a + " needs a value");
        return args[++i];
      };
      if (a == "--carmen") log = value();
      else if (a == "--out") out_dir = value();
      else if (a == "--config") config = value();
      else if (a == "--load") load_path = value();
      else if (a == "--set") {
        const std::string& kv = value();
        const auto eq = kv.find('=');
        if (eq == std::string::npos) throw std::invalid_argument("--set expects key=value, got '" + kv + "'");
        sets.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
      } else if (a == "--limit") {
        limit = cairn::slam_cli::parseInt(value(), "--limit");
        if (limit < 1) throw std::invalid_argument("--limit must be >= 1 scan");
      } else if (a == "--laser-mount")
        laser_mount = value();
      else if (a == "--skip-malformed") skip_malformed = true;
      else if (a == "--json") json = true;
      else if (a == "--quiet") quiet = true;
      else throw std::invalid_argument("run: unknown option '" + a + "'");
    }
    if (log.empty() || out_dir.empty()) throw std::invalid_argument("run needs --carmen <log> and --out <dir>");
    if (laser_mount != "auto" && laser_mount != "zero") throw std::invalid_argument("--laser-mount must be auto or zero");
    std::vector<std::string> keys;
    if (!config.empty()) keys = applyConfig(config, options);
    for (const auto& [k, v] : sets) {
      gs::setSlamParameter(options, k, v);
      keys.push_back(k);
    }
    // A mount given as parameters (laser_x/y/theta) wins over the log's.
    mount_given = std::any_of(keys.begin(), keys.end(), [](const std::string& k) { return k.rfind("laser_", 0) == 0; });
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  try {
    std::filesystem::create_directories(out_dir);
    cairn::sim::CarmenReaderOptions ropt;
    ropt.skip_malformed = skip_malformed;
    std::size_t malformed_warnings = 0;
    ropt.on_warning = [&](const cairn::sim::InputError& w) {
      if (malformed_warnings++ < 5) std::fprintf(stderr, "\ncairn: slam: skipping %s\n", w.what());
    };
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t cpu0 = std::clock();
    const LogScan info = scanLog(log, ropt, limit);
    if (info.backwards > 0)
      std::fprintf(stderr,
                   "cairn: slam: warning: %s:%zu: scan timestamp before an earlier scan's (%zu such scans; "
                   "SLAM rejects them)\n",
                   log.c_str(), info.first_backwards_line, info.backwards);
    malformed_warnings = 0;
    std::size_t total = info.lasers;
    if (limit >= 0) total = std::min(total, static_cast<std::size_t>(limit));
    const bool mount_from_log = laser_mount == "auto" && info.mount && !mount_given;
    if (mount_from_log) options.sensor_in_base = *info.mount;
    gs::GraphSlam slam = load_path.empty() ? gs::GraphSlam(options) : gs::GraphSlam::load(load_path, options);
    cairn::sim::CarmenReader reader(log, ropt);
    cairn::sim::CarmenRecord rec;
    std::size_t done = 0, rejected = 0;
    // Data duration: the span of the scan stamps (not last - first, which is negative when time goes
    // backwards).
    double first_stamp = std::numeric_limits<double>::infinity(), last_stamp = -first_stamp;
    auto last_print = t0;
    while (done < total && reader.next(rec)) {
      auto* laser = std::get_if<cairn::sim::CarmenLaser>(&rec);
      if (laser == nullptr) continue;
      ++done;
      std::optional<gs::Pose2> odom;
      if (laser->has_pose) odom = gs::Pose2{{laser->robot_pose.x, laser->robot_pose.y}, laser->robot_pose.theta};
      first_stamp = std::min(first_stamp, laser->scan.stamp);
      last_stamp = std::max(last_stamp, laser->scan.stamp);
      if (!slam.addScan(laser->scan, odom)) ++rejected;
      const auto now = std::chrono::steady_clock::now();
      if (!quiet && (now - last_print > std::chrono::milliseconds(250) || done == total)) {
        progress(done, total, std::chrono::duration<double>(now - t0).count());
        last_print = now;
      }
    }
    slam.finish();
    const double runtime = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
    if (!quiet) std::fprintf(stderr, "\n");
    if (done == 0) return fail(log + ": no laser scans");
    if (slam.nodes().empty())  // nothing to map (OpenCV would fail on the empty image)
      return fail(log + ": none of the " + std::to_string(done) + " scans was accepted by SLAM (" +
                  std::to_string(rejected) + " rejected: too few valid returns, or time going backwards)");
    const std::filesystem::path dir(out_dir);
    gs::writePoses((dir / "poses.txt").string(), slam.trajectory());
    gs::writeG2o(slam.graph(), (dir / "graph.g2o").string());
    const gs::OccupancyGrid map = slam.map();
    gs::writeMapServer(map, (dir / "map").string());
    std::vector<gs::Pose2> path, loops;
    for (const auto& n : slam.nodes()) path.push_back(n.global_pose);
    for (const auto& e : slam.edges())
      if (e.kind == gs::EdgeKind::kLoop) loops.push_back(slam.nodes()[static_cast<std::size_t>(e.to)].global_pose);
    gs::writeMapPng(map, path, (dir / "map.png").string(), loops);
    slam.save((dir / "state.cslam").string());
    const gs::SlamStats& st = slam.stats();
    const gs::LoopRecall recall = slam.loopRecall();
    const double duration = last_stamp - first_stamp;
    JsonObject j;
    const gs::Pose2& m = options.sensor_in_base;
    j.str("log", log)
        .raw("laser_mount", "[" + cairn::slam_cli::jsonNumber(m.t.x()) + "," + cairn::slam_cli::jsonNumber(m.t.y()) + "," +
                                    cairn::slam_cli::jsonNumber(m.theta) + "]")
        .str("laser_mount_source", mount_from_log ? "log" : "parameters")
        .integer("scans", static_cast<long long>(done))
        .integer("scans_rejected", static_cast<long long>(rejected))
        .integer("nodes", static_cast<long long>(st.nodes))
        .integer("submaps", static_cast<long long>(st.submaps))
        .integer("loop_searches", static_cast<long long>(st.loop_searches))
        .integer("loop_candidates", static_cast<long long>(st.loop_candidates))
        .integer("verifier_rejected", static_cast<long long>(st.verifier_rejected))
        .integer("loop_matches", static_cast<long long>(st.loop_matches))
        .integer("loops_accepted", static_cast<long long>(st.loops_accepted))
        .integer("loops_rejected", static_cast<long long>(st.loops_rejected))
        .integer("loops_inconsistent", static_cast<long long>(slam.inconsistentLoops()))
        .num("loop_precision", st.loops_accepted > 0 ? 1.0 - static_cast<double>(slam.inconsistentLoops()) /
                                                               static_cast<double>(st.loops_accepted)
                                                         : 0.0)
        .integer("revisit_attempts", static_cast<long long>(recall.revisits))
        .num("revisit_recall", recall.revisits > 0 ? static_cast<double>(recall.accepted) / static_cast<double>(recall.revisits) : 0.0)
        .integer("local_recoveries", static_cast<long long>(st.local_recoveries))
        .integer("scans_unmatched", static_cast<long long>(st.scans_unmatched))
        .integer("lost_events", static_cast<long long>(st.lost_events))
        .integer("revisit_localized_scans", static_cast<long long>(st.revisit_scans))
        .integer("localization_matches", static_cast<long long>(st.localization_matches))
        .integer("localization_gated", static_cast<long long>(st.localization_gated))
        .integer("loops_readmitted", static_cast<long long>(st.loops_readmitted))
        .integer("optimizations", static_cast<long long>(st.optimizations))
        .num("data_duration_s", duration)
        .num("runtime_s", runtime)
        .num("real_time_factor", runtime > 0 ? duration / runtime : 0.0)
        .num("cpu_s", cpu)
        .num("real_time_factor_cpu", cpu > 0 ? duration / cpu : 0.0)
        .num("local_time_s", st.local_time_s)
        .num("loop_time_s", st.loop_time_s)
        .num("optimize_time_s", st.optimize_time_s)
        .integer("map_width", map.width)
        .integer("map_height", map.height)
        .num("map_resolution", map.resolution);
    {
      std::ofstream s(dir / "summary.json");
      s << j.text() << "\n";
    }
    if (json) {
      std::cout << j.text() << "\n";
    } else {
      std::printf("%zu scans, %zu nodes, %zu loops accepted (%zu inconsistent), %.1f s for %.1f s of data (%.1fx real time)\n",
                  done, st.nodes, st.loops_accepted, slam.inconsistentLoops(), runtime, duration,
                  runtime > 0 ? duration / runtime : 0.0);
      std::printf("wrote %s/{poses.txt,graph.g2o,map.pgm,map.yaml,map.png,state.cslam,summary.json}\n", out_dir.c_str());
    }
    return 0;
  } catch (const cairn::sim::InputError& e) {
    return fail(e.what());
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}

int slamParamsVerb(const std::vector<std::string>& args) {
  bool markdown = false;
  for (const auto& a : args) {
    if (a == "--markdown") markdown = true;
    else return fail("params: unknown option '" + a + "'");
  }
  const gs::SlamOptions defaults;
  if (markdown) std::printf("| key | default | range | what |\n|---|---|---|---|\n");
  for (const gs::SlamParam& p : gs::slamParameters()) {
    std::string range;
    if (p.min > -1e299 || p.max < 1e299) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "[%g, %g]", p.min, p.max);
      range = buf;
    }
    const std::string value = gs::slamParameterText(defaults, p);
    if (markdown)
      std::printf("| `%s` | %s | %s | %s |\n", p.name.c_str(), value.empty() ? "\"\"" : value.c_str(), range.c_str(),
                  p.description.c_str());
    else
      std::printf("%-28s %-10s %-14s %s\n", p.name.c_str(), value.empty() ? "\"\"" : value.c_str(), range.c_str(),
                  p.description.c_str());
  }
  return 0;
}
