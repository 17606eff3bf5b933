// GraphSlam parameter table (see slam_params.hpp). Seed references: Stüde 2024 §3.2.1 and Appendix A
// ("Indoor" column) for the loop-closure search; Hess et al. 2016 (Cartographer) defaults for local SLAM.
#include "cairn/graph_slam/slam_params.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include "cairn/strict_number.hpp"

namespace cairn::graph_slam {
namespace {

template <typename T>
SlamParam param(std::string name, std::string description, T SlamOptions::*member, double min = -1e300,
                double max = 1e300) {
  return {std::move(name), std::move(description), [member](SlamOptions& o) -> SlamParamRef { return &(o.*member); },
          min, max};
}

template <typename F>
SlamParam nested(std::string name, std::string description, F get, double min = -1e300, double max = 1e300) {
  return {std::move(name), std::move(description), [get](SlamOptions& o) -> SlamParamRef { return get(o); }, min, max};
}

std::vector<SlamParam> makeTable() {
  std::vector<SlamParam> t;
  // sensor mount
  t.push_back(nested("laser_x", "laser mount x in the base frame (m); the component takes it from TF",
                     [](SlamOptions& o) { return &o.sensor_in_base.t.x(); }));
  t.push_back(nested("laser_y", "laser mount y in the base frame (m)", [](SlamOptions& o) { return &o.sensor_in_base.t.y(); }));
  t.push_back(nested("laser_theta", "laser mount yaw in the base frame (rad)",
                     [](SlamOptions& o) { return &o.sensor_in_base.theta; }));
  // scan filter
  t.push_back(nested("filter.min_range", "drop beams shorter than this (m)", [](SlamOptions& o) { return &o.local.filter.min_range; }, 0, 1e3));
  t.push_back(nested("filter.max_range", "longer returns become free-space rays (m); Stüde App. A r_lim = 30 m",
                     [](SlamOptions& o) { return &o.local.filter.max_range; }, 0.1, 1e3));
  t.push_back(nested("filter.voxel_size", "voxel filter of inserted points (m)", [](SlamOptions& o) { return &o.local.filter.voxel_size; }, 0, 10));
  t.push_back(nested("filter.min_points", "adaptive voxel filter keeps at least this many matching points",
                     [](SlamOptions& o) { return &o.local.filter.min_points; }, 1, 1e6));
  t.push_back(nested("filter.max_voxel_size", "adaptive voxel filter's largest voxel (m)",
                     [](SlamOptions& o) { return &o.local.filter.max_voxel_size; }, 0, 10));
  t.push_back(nested("filter.miss_range", "no-return beams become free-space rays of this length (m; 0 disables)",
                     [](SlamOptions& o) { return &o.local.filter.miss_range; }, 0, 1e3));
  // local SLAM
  t.push_back(nested("local.motion_min_distance", "motion filter: new node after this travel (m)",
                     [](SlamOptions& o) { return &o.local.motion_min_distance; }, 0, 100));
  t.push_back(nested("local.motion_min_angle", "motion filter: new node after this rotation (rad)",
                     [](SlamOptions& o) { return &o.local.motion_min_angle; }, 0, 7));
  t.push_back(nested("local.motion_max_time", "motion filter: new node after this time (s)",
                     [](SlamOptions& o) { return &o.local.motion_max_time; }, 0, 1e6));
  t.push_back(nested("local.scans_per_submap", "inserted scans per submap", [](SlamOptions& o) { return &o.local.scans_per_submap; }, 1, 1e6));
  t.push_back(nested("local.use_correlative", "real-time correlative search before refinement",
                     [](SlamOptions& o) { return &o.local.use_correlative; }));
  t.push_back(nested("local.window_linear", "correlative search half window (m)", [](SlamOptions& o) { return &o.local.window.linear; }, 0, 10));
  t.push_back(nested("local.window_angular", "correlative search half window (rad)", [](SlamOptions& o) { return &o.local.window.angular; }, 0, 3.2));
  t.push_back(nested("local.grid_resolution", "submap grid resolution (m)", [](SlamOptions& o) { return &o.local.grid_resolution; }, 0.005, 1));
  t.push_back(nested("local.translation_weight", "refiner: odometry prior weight on translation (1/m)",
                     [](SlamOptions& o) { return &o.local.refine.translation_weight; }, 0, 1e9));
  t.push_back(nested("local.degenerate_translation_weight", "refiner: prior weight along directions the scan does not constrain (1/m; <0: off)",
                     [](SlamOptions& o) { return &o.local.refine.degenerate_translation_weight; }, -1, 1e9));
  t.push_back(nested("local.rotation_weight", "refiner: odometry prior weight on rotation (1/rad)",
                     [](SlamOptions& o) { return &o.local.refine.rotation_weight; }, 0, 1e9));
  t.push_back(nested("local.recovery_score", "below this refined score, a branch-and-bound search over the recovery window (0 disables)",
                     [](SlamOptions& o) { return &o.local.recovery_score; }, 0, 1));
  t.push_back(nested("local.recovery_window_linear", "recovery search half window (m)",
                     [](SlamOptions& o) { return &o.local.recovery_window.linear; }, 0, 20));
  t.push_back(nested("local.recovery_window_angular", "recovery search half window (rad)",
                     [](SlamOptions& o) { return &o.local.recovery_window.angular; }, 0, 3.2));
  t.push_back(nested("local.recovery_min_gain", "a recovered pose must beat the small-window score by this much",
                     [](SlamOptions& o) { return &o.local.recovery_min_gain; }, 0, 1));
  t.push_back(nested("local.unmatched_score", "below this score a scan is not inserted (dead reckoning; 0 disables)",
                     [](SlamOptions& o) { return &o.local.unmatched_score; }, 0, 1));
  t.push_back(nested("local.lost_scans", "this many consecutive unmatched scans: lost, global search (0 disables)",
                     [](SlamOptions& o) { return &o.local.lost_scans; }, 0, 1e6));
  t.push_back(nested("local.judge_min_submap_scans", "scores are judged only against submaps with this many scans",
                     [](SlamOptions& o) { return &o.local.judge_min_submap_scans; }, 0, 1e6));
  t.push_back(nested("local.hit_probability", "grid update probability of a hit", [](SlamOptions& o) { return &o.local.grid.hit_probability; }, 0.5, 1));
  t.push_back(nested("local.miss_probability", "grid update probability of a miss", [](SlamOptions& o) { return &o.local.grid.miss_probability; }, 0, 0.5));
  // graph
  t.push_back(param("odom_sigma_xy", "σ floor of consecutive-node translation (m)", &SlamOptions::odom_sigma_xy, 1e-6, 10));
  t.push_back(param("odom_sigma_theta", "σ floor of consecutive-node rotation (rad)", &SlamOptions::odom_sigma_theta, 1e-6, 10));
  // loop closure — Stüde §3.2.1, Appendix A
  t.push_back(param("loop_closure", "search loop closures", &SlamOptions::loop_closure));
  t.push_back(param("r_min", "minimum loop search radius (m); Stüde eq. 3.8, App. A 3 m", &SlamOptions::r_min, 0, 1e3));
  t.push_back(param("beta", "scale of the uncertainty part of the radius; Stüde eq. 3.8, App. A 0.25", &SlamOptions::beta, 0, 100));
  t.push_back(param("r_max", "cap on the search radius (m)", &SlamOptions::r_max, 0, 1e3));
  t.push_back(param("loop_node_stride", "search loops on every n-th node", &SlamOptions::loop_node_stride, 1, 1e6));
  t.push_back(param("loop_min_time_gap", "candidates at least this old (s)", &SlamOptions::loop_min_time_gap, 0, 1e9));
  t.push_back(param("loop_max_matches", "geometric matches per search", &SlamOptions::loop_max_matches, 1, 1000));
  t.push_back(param("use_verifier", "screen candidates with the AdaBoost verifier (Stüde §3.2.1)", &SlamOptions::use_verifier));
  t.push_back(param("verifier_model", "verifier model file (empty: shipped model)", &SlamOptions::verifier_model));
  t.push_back(param("verifier_threshold_offset", "added to the model's verifier threshold (global search)",
                    &SlamOptions::verifier_threshold_offset, -100, 100));
  t.push_back(param("loop_min_score", "branch-and-bound minimum match score (0..1)", &SlamOptions::loop_min_score, 0, 1));
  t.push_back(param("loop_angular_window", "loop search half angular window (rad)", &SlamOptions::loop_angular_window, 0, 3.15));
  t.push_back(param("bnb_depth", "branch-and-bound precomputation depth", &SlamOptions::bnb_depth, 1, 12));
  t.push_back(param("loop_min_sigma", "minimum σ̂ of loop information (m)", &SlamOptions::loop_min_sigma, 1e-4, 10));
  t.push_back(param("loop_kernel", "robust kernel of loop edges (huber:1, dcs:1, cauchy:1, none)", &SlamOptions::loop_kernel));
  t.push_back(param("loop_confirmations", "further agreeing matches before a local loop is added (0: none)",
                    &SlamOptions::loop_confirmations, 0, 100));
  t.push_back(param("loop_confirm_window", "nodes a pending loop match waits for confirmation", &SlamOptions::loop_confirm_window, 1, 1e6));
  t.push_back(param("loop_confirm_translation", "agreement of confirming matches (m)", &SlamOptions::loop_confirm_translation, 0, 100));
  t.push_back(param("loop_confirm_rotation", "agreement of confirming matches (rad)", &SlamOptions::loop_confirm_rotation, 0, 3.2));
  t.push_back(param("loop_confirm_min_axis_ratio",
                    "two matches both below this translation-information eigenvalue ratio (corridors) do not confirm each other",
                    &SlamOptions::loop_confirm_min_axis_ratio, 0, 1));
  t.push_back(param("loop_readmit_min_set", "agreeing suppressed loops re-admitted with loop_readmit_kernel (0: off)",
                    &SlamOptions::loop_readmit_min_set, 0, 1000));
  t.push_back(param("loop_readmit_window", "nodes back in which suppressed loops are checked for agreement",
                    &SlamOptions::loop_readmit_window, 1, 1e6));
  t.push_back(param("loop_readmit_chi2", "residual χ² from which a loop counts as suppressed", &SlamOptions::loop_readmit_chi2, 0, 1e6));
  t.push_back(param("loop_readmit_min_span", "span of the agreeing loops' query nodes (m)", &SlamOptions::loop_readmit_min_span, 0, 1e4));
  t.push_back(param("loop_readmit_kernel", "robust kernel of re-admitted loops (huber:1, none, ...)", &SlamOptions::loop_readmit_kernel));
  t.push_back(param("verifier_local_threshold", "boosted verifier score needed in the local search",
                    &SlamOptions::verifier_local_threshold, -100, 100));
  t.push_back(param("alpha_min", "global search until n_local/n_WM ≥ α_min; Stüde App. A 0.5", &SlamOptions::alpha_min, 0, 1));
  t.push_back(param("n_start", "verified global links before local search; Stüde App. A 3", &SlamOptions::n_start, 1, 1000));
  t.push_back(param("n_ver", "agreeing detections per global link; Stüde App. A 2", &SlamOptions::n_ver, 0, 1000));
  t.push_back(param("r_ver", "neighbourhood of agreeing detections (m); Stüde App. A 5 m", &SlamOptions::r_ver, 0, 1e3));
  t.push_back(param("global_min_score", "whole-submap match minimum score (0..1)", &SlamOptions::global_min_score, 0, 1));
  // optimization, map
  t.push_back(param("optimize_every_n_nodes", "re-optimize after this many nodes (0: loops only)", &SlamOptions::optimize_every_n_nodes, 0, 1e9));
  t.push_back(param("map_resolution", "occupancy grid resolution (m)", &SlamOptions::map_resolution, 0.005, 10));
  t.push_back(param("localization_only", "localize on a loaded map without extending it", &SlamOptions::localization_only));
  t.push_back(param("revisit_radius", "mapping: no new node within this distance of an older node, localize instead (m; 0: off)",
                    &SlamOptions::revisit_radius, 0, 100));
  t.push_back(param("revisit_angle", "heading difference within which an older node counts as revisited (rad)",
                    &SlamOptions::revisit_angle, 0, 3.15));
  t.push_back(param("revisit_link_scans", "with revisit_radius: inserted scans a new session tries to find itself in the map without nodes (0: off)",
                    &SlamOptions::revisit_link_scans, 0, 1000000));
  t.push_back(param("load_scan_records", "load(): keep the loaded sessions' scan poses (false: the map only)",
                    &SlamOptions::load_scan_records));
  return t;
}

bool parseBool(const std::string& v, bool& out) {
  if (v == "true" || v == "True" || v == "1" || v == "yes") return out = true, true;
  if (v == "false" || v == "False" || v == "0" || v == "no") return out = false, true;
  return false;
}

}  // namespace

const std::vector<SlamParam>& slamParameters() {
  static const std::vector<SlamParam> table = makeTable();
  return table;
}

const SlamParam* findSlamParameter(const std::string& name) {
  for (const auto& p : slamParameters())
    if (p.name == name) return &p;
  return nullptr;
}

void setSlamParameter(SlamOptions& options, const std::string& name, const std::string& value) {
  const SlamParam* p = findSlamParameter(name);
  if (p == nullptr) throw std::invalid_argument(name + ": unknown SLAM parameter");
  const SlamParamRef ref = p->ref(options);
  auto range = [&](double v) {
    if (v >= p->min && v <= p->max) return;
    char buf[64];  // %g: the unbounded default range prints as [-1e+300, 1e+300], not 300 digits
    std::snprintf(buf, sizeof buf, "[%g, %g]", p->min, p->max);
    throw std::invalid_argument(name + ": " + value + " is outside " + buf);
  };
  if (auto* d = std::get_if<double*>(&ref)) {
    const auto v = strict_number::parse_finite(value);
    if (!v) throw std::invalid_argument(name + ": expected a number, got '" + value + "'");
    range(*v);
    **d = *v;
  } else if (auto* i = std::get_if<int*>(&ref)) {
    const auto v = strict_number::parse_integer(value);
    if (!v || *v < std::numeric_limits<int>::min() || *v > std::numeric_limits<int>::max())
      throw std::invalid_argument(name + ": expected an integer, got '" + value + "'");
    range(static_cast<double>(*v));
    **i = static_cast<int>(*v);
  } else if (auto* b = std::get_if<bool*>(&ref)) {
    if (!parseBool(value, **b)) throw std::invalid_argument(name + ": expected true or false, got '" + value + "'");
  } else {
    *std::get<std::string*>(ref) = value;
  }
}

std::string slamParameterText(const SlamOptions& options, const SlamParam& param) {
  SlamOptions copy = options;
  const SlamParamRef ref = param.ref(copy);
  if (auto* d = std::get_if<double*>(&ref)) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%g", **d);
    return buf;
  }
  if (auto* i = std::get_if<int*>(&ref)) return std::to_string(**i);
  if (auto* b = std::get_if<bool*>(&ref)) return **b ? "true" : "false";
  return *std::get<std::string*>(ref);
}

}  // namespace cairn::graph_slam
