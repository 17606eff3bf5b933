#include "tool_bench.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cairn/people_tracking/bench.hpp"
#include "cli_parse.hpp"
#ifdef CAIRN_PEOPLE_SIM
#include <memory>

#include "cairn/sim/world.hpp"
#include "sim_training.hpp"
#endif

using namespace cairn::people_tracking;

int runBenchVerb(int argc, char** argv) {
  BenchParams p;
  bool json = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError("option " + a + " needs a value");
      return argv[++i];
    };
    auto number = [&](const std::string& v) { return parseNumber(a, v); };
    auto integer = [&](const std::string& v, long long lo, long long hi) { return parseInteger(a, v, lo, hi); };
    // Options that set a core parameter check the component's range for it (param_ranges.hpp).
    auto param = [&](const std::string& v, std::string_view name) { return parseParam(a, v, name); };
    auto integerParam = [&](const std::string& v, std::string_view name) { return parseIntegerParam(a, v, name); };
    if (a == "--json") json = true;
    else if (a == "--world") p.world = value();
    else if (a == "--trajectories") p.trajectories = value();
    else if (a == "--robot-path") p.robot_path = value();
    else if (a == "--seed") p.seed = static_cast<std::uint64_t>(integer(value(), 0, kMaxSeed));
    else if (a == "--duration") p.duration = number(value());
    else if (a == "--start") p.start = number(value());
    else if (a == "--rate") p.scan_rate = number(value());
    else if (a == "--smooth") p.trajectory_smoothing = number(value());
    else if (a == "--fix-id-swaps") p.fix_id_exchanges = true;
    else if (a == "--camera") p.camera.fov = number(value()) * M_PI / 180.0;
    else if (a == "--camera-range") p.camera.range = number(value());
    else if (a == "--camera-bearing-sigma") p.camera.bearing_sigma = number(value()) * M_PI / 180.0;
    else if (a == "--camera-range-sigma") p.camera.range_sigma = number(value());
    else if (a == "--camera-pd") p.camera.detection_probability = number(value());
    else if (a == "--camera-false") p.camera.false_per_scan = number(value());
    else if (a == "--fusion-distance") p.tracker.fusion.max_pair_distance = param(value(), "fusion.max_pair_distance");
    else if (a == "--fusion-gate") p.tracker.fusion.gate_chi2 = param(value(), "fusion.gate_chi2");
    else if (a == "--model") p.model = value();
    else if (a == "--association") p.tracker.association = associationFromString(value());
    else if (a == "--dump") p.dump_dir = value();
    else if (a == "--process-noise") p.tracker.process_noise = param(value(), "tracker.process_noise");
    else if (a == "--maneuver-noise") p.tracker.maneuver_process_noise = param(value(), "tracker.maneuver_process_noise");
    else if (a == "--maneuver-rate") p.tracker.maneuver_rate = param(value(), "tracker.maneuver_rate");
    else if (a == "--maneuver-gate") p.tracker.maneuver_gate_sigma = param(value(), "tracker.maneuver_gate_sigma");
    else if (a == "--maneuver-gate-time") p.tracker.maneuver_gate_time = param(value(), "tracker.maneuver_gate_time");
    else if (a == "--maneuver-end-rate") p.tracker.maneuver_end_rate = param(value(), "tracker.maneuver_end_rate");
    else if (a == "--adaptive-nis") p.tracker.adaptive_nis_threshold = param(value(), "tracker.adaptive_nis_threshold");
    else if (a == "--adaptive-gain") p.tracker.adaptive_noise_gain = param(value(), "tracker.adaptive_noise_gain");
    else if (a == "--adaptive-smoothing") p.tracker.adaptive_nis_smoothing = param(value(), "tracker.adaptive_nis_smoothing");
    else if (a == "--delete-timeout") p.tracker.delete_timeout = param(value(), "tracker.delete_timeout");
    else if (a == "--max-position-sigma") p.tracker.max_position_sigma = param(value(), "tracker.max_position_sigma");
    else if (a == "--confirm-score") p.tracker.confirm_score = param(value(), "tracker.confirm_score");
    else if (a == "--confirm-hits") p.tracker.confirm_hits = static_cast<int>(integerParam(value(), "tracker.confirm_hits"));
    else if (a == "--oracle-detections") p.oracle_detections = true;
    else if (a == "--static-map") p.static_map = true;
    else if (a == "--static-map-margin") p.tracker.static_map_margin = param(value(), "static_map.margin");
    else if (a == "--oracle-sigma") p.oracle_sigma = number(value());
    else if (a == "--pairing") {
      const std::string v = value();
      if (v != "tracks" && v != "detector") throw InputError("--pairing expects tracks|detector, got '" + v + "'");
      p.track_aware_pairing = v == "tracks";
    }
    else if (a == "--leg-spread") p.tracker.leg_spread_sigma = param(value(), "tracker.leg_spread_sigma");
    else if (a == "--leg-spread-lateral") p.tracker.leg_spread_lateral_sigma = param(value(), "tracker.leg_spread_lateral_sigma");
    else if (a == "--beams") p.laser_beams = static_cast<int>(integer(value(), 8, 100000));
    else if (a == "--leg-gate") p.tracker.leg_gate_chi2 = param(value(), "tracker.leg_gate_chi2");
    else if (a == "--confidence-cost") p.tracker.confidence_cost = param(value(), "tracker.confidence_cost");
    else if (a == "--confidence-gain") p.tracker.confidence_gain = param(value(), "tracker.confidence_gain");
    else if (a == "--reid-window") p.tracker.reid_window = param(value(), "tracker.reid_window");
    else if (a == "--reid-max-distance") p.tracker.reid_max_distance = param(value(), "tracker.reid_max_distance");
    else if (a == "--publish-coast") p.tracker.publish_coast_time = param(value(), "tracker.publish_coast_time");
    else if (a == "--occluded-coast") p.tracker.occluded_coast_time = param(value(), "tracker.occluded_coast_time");
    else if (a == "--occluded-delete-timeout") p.tracker.occluded_delete_timeout = param(value(), "tracker.occluded_delete_timeout");
    else if (a == "--free-space-delete") p.tracker.free_space_delete_scans = static_cast<int>(integerParam(value(), "tracker.free_space_delete_scans"));
    else if (a == "--standing-time") p.tracker.standing_time = param(value(), "tracker.standing_time");
    else if (a == "--standing-speed") p.tracker.standing_speed = param(value(), "tracker.standing_speed");
    else if (a == "--standing-noise") p.tracker.standing_position_noise = param(value(), "tracker.standing_position_noise");
    else if (a == "--split-scans") p.tracker.split_scans = static_cast<int>(integerParam(value(), "tracker.split_scans"));
    else if (a == "--visibility-radius") p.tracker.visibility_radius = param(value(), "tracker.visibility_radius");
    else if (a == "--min-init-distance") p.tracker.min_init_distance = param(value(), "tracker.min_init_distance");
    else if (a == "--joint-pairs") p.tracker.joint_pairs_max_nodes = static_cast<int>(integerParam(value(), "tracker.joint_pairs_max_nodes"));
    else if (a == "--single-leg-stride") p.tracker.single_leg_stride_sigma = param(value(), "tracker.single_leg_stride_sigma");
    else if (a == "--initial-velocity-sigma") p.tracker.initial_velocity_sigma = param(value(), "tracker.initial_velocity_sigma");
    else if (a == "--track-leg-confidence") p.detector.track_leg_confidence = param(value(), "detector.track_leg_confidence");
    else if (a == "--track-leg-confidence-with-map")
      p.detector.track_leg_confidence_with_map = param(value(), "detector.track_leg_confidence_with_map");
    else if (a == "--moving-fraction") p.detector.moving_fraction = param(value(), "detector.moving_fraction");
    else if (a == "--moving-track-leg-confidence") p.detector.moving_track_leg_confidence = param(value(), "detector.moving_track_leg_confidence");
    else if (a == "--moving-min-leg-confidence") p.detector.moving_min_leg_confidence = param(value(), "detector.moving_min_leg_confidence");
    else if (a == "--motion-window") p.motion.window = param(value(), "motion.window");
    else if (a == "--motion-memory") p.motion.memory = param(value(), "motion.memory");
    else if (a == "--crossed-track-leg-confidence")
      p.detector.crossed_track_leg_confidence = param(value(), "detector.crossed_track_leg_confidence");
    else if (a == "--motion-min-age") p.motion.min_age = param(value(), "motion.min_age");
    else if (a == "--motion-margin") p.motion.margin = param(value(), "motion.margin");
    else if (a == "--motion-slope-factor") p.motion.slope_factor = param(value(), "motion.slope_factor");
    else if (a == "--motion-min-free-scans")
      p.motion.min_free_scans = static_cast<std::size_t>(integerParam(value(), "motion.min_free_scans"));
    else if (a == "--single-leg-min-confidence")
      p.detector.single_leg_min_confidence = param(value(), "detector.single_leg_min_confidence");
    else if (a == "--min-leg-confidence") p.detector.min_leg_confidence = param(value(), "detector.min_leg_confidence");
    else if (a == "--pair-distance") p.detector.max_leg_pair_distance = param(value(), "detector.max_leg_pair_distance");
    else if (a == "--min-points") p.detector.segmentation.min_points = static_cast<int>(integerParam(value(), "segmentation.min_points"));
    else if (a == "--split-min-width") p.detector.split_min_width = param(value(), "detector.split_min_width");
    else if (a == "--split-gap-ratio") p.detector.split_gap_ratio = param(value(), "detector.split_gap_ratio");
    else if (a == "--split-min-gap-beams") p.detector.split_min_gap_beams = param(value(), "detector.split_min_gap_beams");
    else if (a == "--small-cluster-min-range")
      p.detector.small_cluster_min_range = param(value(), "detector.small_cluster_min_range");
    else if (a == "--sigma-pair") p.detector.sigma_pair = param(value(), "detector.sigma_pair");
    else if (a == "--sigma-single") p.detector.sigma_single = param(value(), "detector.sigma_single");
    else if (a == "--trajectory-offset") {  // x,y[,theta]: world = offset (+) data
      const std::string v = value();
      std::vector<double> xyt;
      for (const std::string& field : splitCommas(v)) xyt.push_back(number(field));
      if (xyt.size() < 2 || xyt.size() > 3) throw InputError("--trajectory-offset expects x,y or x,y,theta, got '" + v + "'");
      p.trajectory_offset = Pose2{xyt[0], xyt[1], xyt.size() == 3 ? xyt[2] : 0.0};
    }
    else throw InputError("unknown bench option '" + a + "'");
  }
  if (p.trajectories.empty()) throw InputError("bench needs --trajectories FILE");
  if (p.trajectory_offset && p.world == "auto") throw InputError("--trajectory-offset needs a --world other than auto");
#ifdef CAIRN_PEOPLE_SIM
  if (p.world != "auto") {
    std::shared_ptr<const cairn::sim::World> world;
    try {
      world = std::make_shared<const cairn::sim::World>(cairn::sim::loadWorld(cairn::sim::resolveWorldPath(p.world)));
    } catch (const cairn::sim::InputError& e) {
      throw InputError(std::string("--world: ") + e.what());
    }
    p.robot_start = Pose2{world->robot_start.x, world->robot_start.y, world->robot_start.theta};
    p.world_geometry = [world](double t, Scene& scene) { addWorldGeometry(*world, t, scene); };
    if (p.robot_path.rfind("route:", 0) == 0) {  // route:NAME[:SPEED], a route of this world
      const std::string spec = p.robot_path.substr(6);
      const std::size_t colon = spec.find(':');
      const std::string name = spec.substr(0, colon);
      if (colon != std::string::npos) p.robot_route_speed = parseNumber("--robot-path", spec.substr(colon + 1));
      const auto route = world->routes.find(name);
      if (route == world->routes.end())
        throw InputError("--robot-path " + p.robot_path + ": world '" + p.world + "' has no route '" + name + "'");
      for (const auto& q : route->second) p.robot_route.emplace_back(q.x, q.y);
    }
  }
#endif
  const BenchResult r = runBench(p);
  if (json) {
    std::printf("%s\n", benchJson(p, r).c_str());
  } else {
    std::printf("%s (%s): %zu scans, %.1f s, %.1f people counted per scan on average\n", p.trajectories.c_str(),
                r.format.c_str(), r.scans, r.duration, r.mean_people_counted);
    for (const auto& [name, b] : {std::pair{"cairn", &r.cairn}, std::pair{"baseline", &r.baseline}})
      std::printf("  %-8s MOTA %.3f  MOTP %.3f m  IDSW %zu (%.2f per 100 tracks)  FP %zu  FN %zu  HOTA %.3f (DetA %.3f "
                  "AssA %.3f LocA %.3f)  IDF1 %.3f  OSPA %.3f m  %.0f scans/s\n", name,
                  b->mot.mota(), b->mot.motp(), b->mot.id_switches, b->mot.idSwitchesPer100Tracks(), b->mot.fp,
                  b->mot.fn, b->hota.hota, b->hota.deta, b->hota.assa, b->hota.loca, b->id.idf1, b->ospa, b->scansPerSecond(r.scans));
  }
  return 0;
}
