#include "cairn/people_tracking/param_ranges.hpp"

#include <cstdio>
#include <stdexcept>

namespace cairn::people_tracking {

namespace {
// Units and meaning: the component's parameter descriptions (component README, "Parameters").
struct Entry {
  std::string_view name;
  ParamRange range;
};
constexpr Entry kRanges[] = {
    {"segmentation.jump_base", {0.0, 2.0}},
    {"segmentation.jump_beam_factor", {0.0, 50.0}},
    {"segmentation.max_gap_beams", {0.0, 20.0}},
    {"segmentation.min_points", {1.0, 1000.0}},
    {"segmentation.max_points", {1.0, 100000.0}},
    {"segmentation.jump_cap", {0.0, 100.0}},
    {"detector.min_leg_confidence", {0.0, 1.0}},
    {"detector.track_leg_confidence", {0.0, 1.0}},
    {"detector.track_leg_confidence_with_map", {0.0, 1.0}},
    {"detector.moving_fraction", {0.0, 1.0}},
    {"detector.moving_track_leg_confidence", {0.0, 1.0}},
    {"detector.crossed_track_leg_confidence", {0.0, 1.0}},
    {"detector.moving_min_leg_confidence", {0.0, 1.0}},
    {"detector.max_range", {0.1, 100.0}},
    {"detector.small_cluster_min_range", {0.0, 100.0}},
    {"detector.max_leg_width", {0.01, 2.0}},
    {"detector.split_min_width", {0.0, 2.0}},
    {"detector.split_gap_ratio", {1.0, 100.0}},
    {"detector.split_min_gap_beams", {1.0, 100.0}},
    {"detector.leg_center_offset", {0.0, 0.5}},
    {"detector.max_leg_pair_distance", {0.0, 3.0}},
    {"detector.single_leg_min_confidence", {0.0, 1.0}},
    {"detector.sigma_pair", {1e-4, 5.0}},
    {"detector.sigma_single", {1e-4, 5.0}},
    {"tracker.process_noise", {1e-6, 100.0}},
    {"tracker.maneuver_process_noise", {0.0, 1000.0}},
    {"tracker.maneuver_rate", {0.0, 100.0}},
    {"tracker.maneuver_end_rate", {0.0, 100.0}},
    {"tracker.adaptive_nis_threshold", {0.0, 1000.0}},
    {"tracker.adaptive_noise_gain", {1.0, 10000.0}},
    {"tracker.adaptive_nis_smoothing", {0.0, 1.0}},
    {"tracker.initial_velocity_sigma", {1e-3, 10.0}},
    {"tracker.gate_chi2", {0.1, 100.0}},
    {"tracker.confirm_hits", {1.0, 100.0}},
    {"tracker.confirm_score", {0.0, 100.0}},
    {"tracker.tentative_timeout", {0.0, 60.0}},
    {"tracker.delete_timeout", {0.0, 60.0}},
    {"tracker.max_position_sigma", {0.01, 100.0}},
    {"tracker.min_init_distance", {0.0, 5.0}},
    {"tracker.publish_coast_time", {0.0, 60.0}},
    {"tracker.max_dt", {0.01, 3600.0}},
    {"tracker.detection_probability", {0.01, 1.0}},
    {"tracker.clutter_density", {1e-9, 100.0}},
    {"tracker.jpda_max_events", {1.0, 1e7}},
    {"tracker.min_detection_confidence", {0.0, 1.0}},
    {"tracker.confidence_gain", {0.0, 1.0}},
    {"tracker.leg_spread_sigma", {0.01, 2.0}},
    {"tracker.leg_spread_lateral_sigma", {0.01, 2.0}},
    {"tracker.leg_spread_min_speed", {0.0, 10.0}},
    {"tracker.leg_gate_chi2", {0.1, 100.0}},
    {"tracker.confidence_cost", {0.0, 100.0}},
    {"tracker.maneuver_gate_sigma", {0.0, 2.0}},
    {"tracker.maneuver_gate_time", {0.05, 5.0}},
    {"tracker.reid_window", {0.0, 60.0}},
    {"tracker.reid_gate_chi2", {0.1, 100.0}},
    {"tracker.reid_max_distance", {0.0, 1000.0}},
    {"tracker.visibility_radius", {0.05, 2.0}},
    {"tracker.occluded_coast_time", {0.0, 60.0}},
    {"tracker.occluded_delete_timeout", {0.0, 60.0}},
    {"tracker.free_space_delete_scans", {1.0, 1000.0}},
    {"tracker.standing_time", {0.0, 60.0}},
    {"tracker.standing_speed", {0.01, 2.0}},
    {"tracker.standing_position_noise", {0.0, 10.0}},
    {"tracker.split_scans", {0.0, 1000.0}},
    {"tracker.joint_pairs_max_nodes", {0.0, 10000000.0}},
    {"tracker.single_leg_stride_sigma", {0.0, 2.0}},
    {"fusion.max_pair_distance", {0.0, 10.0}},
    {"fusion.gate_chi2", {0.0, 100.0}},
    {"static_map.margin", {0.0, 2.0}},
    {"motion.window", {0.0, 10.0}},
    {"motion.min_age", {0.0, 10.0}},
    {"motion.margin", {0.0, 2.0}},
    {"motion.slope_factor", {0.0, 10.0}},
    {"motion.min_free_scans", {1.0, 64.0}},
    {"motion.memory", {0.0, 86400.0}},
    {"motion.memory_resolution", {0.02, 1.0}},
    {"motion.memory_size", {4.0, 400.0}},
    {"motion.memory_surface_gap", {0.0, 10.0}},
    {"guide.field_radius", {0.1, 100.0}},
    {"guide.select_max_distance", {0.1, 100.0}},
    {"guide.lost_timeout", {0.0, 60.0}},
    {"guide.reacquire_radius", {0.0, 20.0}},
    {"guide.reacquire_window", {0.0, 3600.0}},
    {"guide.field_half_angle_deg", {1.0, 180.0}},
    {"mask.leg_radius", {0.0, 1.0}},
    {"mask.margin", {0.0, 2.0}},
    {"mask.default_radius", {0.05, 3.0}},
    {"mask.min_radius", {0.0, 3.0}},
};
}  // namespace

ParamRange paramRange(std::string_view name) {
  for (const Entry& e : kRanges)
    if (e.name == name) return e.range;
  throw std::out_of_range("no range for parameter '" + std::string(name) + "'");
}

std::string numberText(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

std::string rangeText(const ParamRange& r) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "[%g, %g]", r.lo, r.hi);
  return buf;
}

}  // namespace cairn::people_tracking
