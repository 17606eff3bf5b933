// Local SLAM speed on a CARMEN log (default: ACES): per-scan time of LocalSlam::addScan (filtering, real-time
// CSM, refinement, insertion) with and without the correlative matcher, and branch-and-bound against
// exhaustive correlative search on a wide window over finished submaps — all measured in the same run.
//   cairn-slam-local-bench [log] [--max-scans N] [--poses out.txt]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <variant>
#include <vector>

#include "cairn/graph_slam/correlative_matcher.hpp"
#include "cairn/graph_slam/local_slam.hpp"
#include "cairn/sim/carmen.hpp"

namespace gs = cairn::graph_slam;
namespace sim = cairn::sim;
using Clock = std::chrono::steady_clock;

namespace {

struct Scan {
  double stamp;
  gs::Pose2 odom, mount;
  sim::LaserScan scan;
};

struct RunStats {
  std::vector<double> ms;
  double total_s = 0;
  std::size_t inserted = 0, finished = 0;
  std::vector<std::shared_ptr<const gs::Submap>> submaps;
  std::vector<gs::LocalResult> results;
};

RunStats run(const std::vector<Scan>& scans, const gs::LocalSlamOptions& o, bool keep) {
  RunStats st;
  gs::LocalSlam slam(o);
  st.ms.reserve(scans.size());
  for (const auto& s : scans) {
    const auto t0 = Clock::now();
    auto r = slam.addScan(s.stamp, gs::toRangeData(s.scan, s.mount, o.filter), s.odom);
    const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
    st.ms.push_back(1e3 * dt);
    st.total_s += dt;
    if (r && keep) st.results.push_back(std::move(*r));
  }
  st.inserted = slam.scansInserted();
  st.submaps = slam.finishedSubmaps();
  st.finished = st.submaps.size();
  return st;
}

void report(const char* name, RunStats st, double log_s) {
  std::sort(st.ms.begin(), st.ms.end());
  const double mean = st.total_s * 1e3 / static_cast<double>(st.ms.size());
  std::printf("%-28s %6zu scans  mean %.3f ms  p50 %.3f  p99 %.3f  max %.3f ms  total %.2f s  %.0fx real time  (%zu inserted, %zu submaps)\n",
              name, st.ms.size(), mean, st.ms[st.ms.size() / 2], st.ms[st.ms.size() * 99 / 100], st.ms.back(),
              st.total_s, log_s / st.total_s, st.inserted, st.finished);
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = "/work/shared/data/slam_logs_carmen/radish/aces.clf.bz2";
  std::size_t max_scans = 0;
  std::string poses_out;
  gs::LocalSlamOptions def;
  bool run_baseline = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--max-scans") && i + 1 < argc) {
      max_scans = static_cast<std::size_t>(std::atol(argv[++i]));
    } else if (!std::strcmp(argv[i], "--poses") && i + 1 < argc) {
      poses_out = argv[++i];
    } else if (!std::strcmp(argv[i], "--set") && i + 2 < argc) {  // --set <option> <value> (tuning)
      const std::string k = argv[++i];
      const double v = std::atof(argv[++i]);
      if (k == "translation_weight") def.refine.translation_weight = v;
      else if (k == "rotation_weight") def.refine.rotation_weight = v;
      else if (k == "occupied_weight") def.refine.occupied_weight = v;
      else if (k == "linear") def.window.linear = v;
      else if (k == "angular") def.window.angular = v;
      else if (k == "csm_translation_weight") def.window.translation_weight = v;
      else if (k == "csm_rotation_weight") def.window.rotation_weight = v;
      else if (k == "max_step_range") def.window.max_step_range = v;
      else if (k == "use_correlative") def.use_correlative = v != 0.0;
      else if (k == "scans_per_submap") def.scans_per_submap = static_cast<int>(v);
      else if (k == "min_points") def.filter.min_points = static_cast<int>(v);
      else if (k == "max_voxel_size") def.filter.max_voxel_size = v;
      else if (k == "max_range") def.filter.max_range = v;
      else if (k == "hit_probability") def.grid.hit_probability = v;
      else if (k == "miss_probability") def.grid.miss_probability = v;
      else if (k == "baseline") run_baseline = v != 0.0;
      else {
        std::fprintf(stderr, "cairn: --set: unknown option '%s'\n", k.c_str());
        return 2;
      }
    } else {
      path = argv[i];
    }
  }
  std::vector<Scan> scans;
  try {
    sim::CarmenReader reader(path);
    sim::CarmenRecord rec;
    while (reader.next(rec)) {
      if (auto* l = std::get_if<sim::CarmenLaser>(&rec)) {
        if (!l->has_pose || l->message != "FLASER") continue;
        const gs::Pose2 robot = gs::toPose2(l->robot_pose), laser = gs::toPose2(l->laser_pose);
        scans.push_back({l->scan.stamp, robot, gs::compose(gs::inverse(robot), laser), l->scan});
        if (max_scans && scans.size() >= max_scans) break;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn: %s\n", e.what());
    return 2;
  }
  if (scans.size() < 2) {
    std::fprintf(stderr, "cairn: %s:0: fewer than 2 FLASER scans\n", path.c_str());
    return 2;
  }
  const double log_s = scans.back().stamp - scans.front().stamp;
  std::printf("log %s: %zu scans over %.1f s (budget for 20x real time: %.2f ms/scan for the whole SLAM)\n", path.c_str(),
              scans.size(), log_s, 1e3 * log_s / 20.0 / static_cast<double>(scans.size()));

  RunStats full = run(scans, def, !poses_out.empty());
  report("local SLAM (CSM + refine)", full, log_s);
  if (run_baseline) {
    gs::LocalSlamOptions no_csm = def;
    no_csm.use_correlative = false;
    report("baseline: refine only", run(scans, no_csm, false), log_s);
  }

  if (!poses_out.empty()) {
    std::ofstream f(poses_out);
    for (const auto& r : full.results) {
      f << std::fixed;
      f.precision(6);
      f << r.stamp << ' ' << r.local_pose.t.x() << ' ' << r.local_pose.t.y() << ' ' << r.local_pose.theta << '\n';
    }
    std::printf("wrote %zu local poses to %s\n", full.results.size(), poses_out.c_str());
  }

  // Branch and bound vs exhaustive search: re-match inserted scans against the finished submap they went into
  // over a +-1 m, +-0.5 rad window from a 0.5 m / 0.2 rad perturbed guess.
  if (run_baseline && !full.submaps.empty()) {
    gs::SearchWindow w;
    w.linear = 1.0;
    w.angular = 0.5;
    w.translation_weight = w.rotation_weight = 0.0;
    double t_bnb = 0, t_brute = 0, t_pre = 0;
    int n = 0, same = 0;
    const std::size_t stride = std::max<std::size_t>(1, scans.size() / 40);
    // Keep some inserted scans with the submap they went into; match them once that submap is finished.
    gs::LocalSlam slam(def);
    std::vector<std::pair<gs::LocalResult, std::shared_ptr<const gs::Submap>>> picks;
    for (std::size_t i = 0; i < scans.size() && picks.size() < 20; ++i) {
      auto r = slam.addScan(scans[i].stamp, gs::toRangeData(scans[i].scan, scans[i].mount, def.filter), scans[i].odom);
      if (r && r->inserted && i % stride == 0 && !r->insertion_submaps.empty() && r->insertion_submaps.front()->num_scans > 20) {
        picks.emplace_back(*r, r->insertion_submaps.front());
      }
      for (const auto& f : slam.takeNewlyFinished()) {
        for (auto& p : picks) {
          if (p.second == f) {
            const auto t0 = Clock::now();
            const gs::BranchAndBoundMatcher bnb(f->grid, 7);
            t_pre += std::chrono::duration<double>(Clock::now() - t0).count();
            const gs::Pose2 in_grid = gs::compose(gs::inverse(f->local_pose), p.first.local_pose);
            const gs::Pose2 guess = gs::compose(in_grid, gs::Pose2{Eigen::Vector2d(0.5, -0.4), 0.2});
            const auto t1 = Clock::now();
            const auto a = bnb.match(p.first.matching_points, guess, w, 0.3);
            const auto t2 = Clock::now();
            const auto b = gs::correlativeMatch(f->grid, p.first.matching_points, guess, w, 0.3);
            const auto t3 = Clock::now();
            t_bnb += std::chrono::duration<double>(t2 - t1).count();
            t_brute += std::chrono::duration<double>(t3 - t2).count();
            ++n;
            if (a && b && std::abs(a->score - b->score) < 1e-6) ++same;
          }
        }
      }
    }
    if (n > 0) {
      std::printf("wide window +-1 m +-0.5 rad, %d matches: branch and bound %.2f ms/match (precompute %.1f ms/submap), "
                  "exhaustive CSM %.2f ms/match: %.1fx faster, same optimum in %d/%d\n",
                  n, 1e3 * t_bnb / n, 1e3 * t_pre / n, 1e3 * t_brute / n, t_brute / std::max(t_bnb, 1e-12), same, n);
    }
  }
  return 0;
}
