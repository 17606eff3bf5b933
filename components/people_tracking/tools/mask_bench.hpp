#pragma once

// `cairn people mask-bench`: SLAM with and without the guide masked (Yuan §3.2.2, Tables 3.1/3.2). Built when the
// SLAM front end and the simulator are part of the build (tool-side library; the core does not depend on them).
#include <cstddef>
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "cairn/people_tracking/detector.hpp"
#include "cairn/people_tracking/masking.hpp"

namespace cairn::people_tracking {

struct MaskBenchParams {
  std::string world = "apartment";
  std::string route = "home_tour";
  std::uint64_t seed = 1;
  double speed = 0.5;       // m/s, guide and robot
  double lead = 1.2;        // m, guide starts this far ahead along the route
  double max_duration = 400.0;
  double heading_drift = 0.03;  // rad/m, odometry heading drift (as in the SLAM pipeline test): SLAM must match
  double scale_error = 0.03;    // odometry scale error
  bool follow = true;           // robot follows the tracked guide (Yuan's setting); false: drives the route itself
  bool keep_spurs = false;      // guide walks the route as is (with out-and-back spurs); default: spurs removed
  double follow_distance = 1.2; // m, the robot stops closer than this to the guide (choice; Yuan gives no value)
  double max_v = 0.7;           // m/s, following speed limit
  double max_w = 1.0;           // rad/s
  std::string model;            // leg classifier ("" = the shipped default AdaBoost model)
  DetectorParams detector;      // the guide's leg detector (--min-points: its segmentation's smallest cluster)
  double fov_deg = 360.0;       // laser field of view (Yuan's robot: a front laser; 180 deg is the closer setting)
  double range_max = 20.0;      // m, laser range (sim default; SICK LMS 200 ~8 m indoors, Hokuyo URG-04LX 4-5.6 m)
  MaskMode mask = MaskMode::kTangents;  // Yuan's tangent mask, or cairn's returns-inside variant
  bool json = false;
};

struct MaskBenchError {
  double rmse = 0.0, mean = 0.0, max = 0.0;  // m, ATE after rigid 2D alignment to ground truth
};

// Occupied cells of a SLAM map; spurious: farther than 0.15 m from every wall, door and piece of furniture;
// leg imprints: spurious cells within 0.5 m of the guide's true path (Yuan Figs. 3.4-3.6).
struct MaskBenchMap {
  std::size_t occupied = 0, spurious = 0, imprints = 0;
};

struct MaskBenchResult {
  double duration = 0.0;  // s
  std::size_t scans = 0;
  double travelled = 0.0;  // m, robot
  double guide_in_field = 0.0, guide_mean_distance = 0.0, stalled = 0.0, guide_tracked = 0.0;  // fractions of scans
  std::size_t recovery_scans = 0;
  double masked_beams_per_tracked_scan = 0.0;
  MaskBenchError odometry, unmasked, masked;
  MaskBenchMap map_unmasked, map_masked;
};

// Runs one simulation; the same scans feed both SLAM instances. Throws InputError for a bad world or route.
MaskBenchResult runMaskBench(const MaskBenchParams& params);

// The CLI verb (argv[1] == "mask-bench"): parses the options, runs, prints text or JSON.
int runMaskBenchVerb(int argc, char** argv);

}  // namespace cairn::people_tracking
