// Tracker benchmark: walkers replay recorded trajectories in a generated scene (legs with gait, laser noise),
// a static or moving robot scans them, and the tracker output is scored with CLEAR MOT against the people that
// are within sensor range and line of sight (also with HOTA, IDF1 and OSPA, track_metrics.hpp). A baseline tracker runs on the same detections in the same run.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cairn/people_tracking/clear_mot.hpp"
#include "cairn/people_tracking/scene.hpp"
#include "cairn/people_tracking/tracker.hpp"
#include "cairn/people_tracking/trajectories.hpp"
#include "cairn/people_tracking/track_metrics.hpp"

namespace cairn::people_tracking {

// A second detection source for the bench (`--camera`): a person detector of another modality, e.g. a camera
// whose image detections are projected onto the ground plane, modelled by its errors rather than rendered: it
// reports each counted person (the laser's line-of-sight rule; no seeing over people) inside its field of view
// with probability detection_probability, at the true position with Gaussian noise in bearing and in range
// (proportional to the distance, as ground-plane projection is), plus Poisson false detections uniform in its
// field. All values are assumptions (no camera data ship with cairn); docs/benchmarks.md says which were used.
struct CameraModel {
  double fov = 0.0;                    // rad, centred on the robot's heading; 0 = no camera
  double range = 10.0;                 // m
  double bearing_sigma = 0.0175;       // rad (1 deg)
  double range_sigma = 0.05;           // relative: std = range_sigma * distance (at least 0.05 m)
  double detection_probability = 0.9;
  double false_per_scan = 0.05;        // mean number of false detections per scan
};

struct BenchParams {
  std::string trajectories;
  // "auto": open walled area around the trajectories, robot at its centre. Any other name needs world_geometry
  // (the tool fills it from a components/sim world when built with the simulator).
  std::string world = "auto";
  // Static and scheduled geometry of the world at time t (walls, doors, furniture, markers), appended to scene.
  std::function<void(double t, Scene& scene)> world_geometry;
  Pose2 robot_start{};  // world: the static robot's pose, and the centre of circle:R paths
  // world: world = trajectory_offset (+) data. Unset: the trajectories' bounding-box centre goes to robot_start.
  std::optional<Pose2> trajectory_offset;
  // The tracker gets the world's static geometry (the auto world's walls, or world_geometry at the start time)
  // as a static map (static_map.hpp): legs next to it are dropped.
  bool static_map = false;
  // Walkers replay the annotations smoothed with smoothTrajectories(sigma = this, s); 0 = linear interpolation
  // of the raw annotations (default). Ground truth is where the walkers are, so it is smoothed too.
  double trajectory_smoothing = 0.0;
  // Undo the recording's id exchanges (fixIdExchanges; before smoothing) — diagnostic, default off: the walkers
  // replay the annotations as recorded.
  bool fix_id_exchanges = false;
  // "" static; "circle:R" circles the centre at 0.4 m/s; "route:NAME[:SPEED]" drives robot_route (the caller puts
  // the world's route NAME there) in a loop at robot_route_speed, turning in place at 1 rad/s; or CSV t,x,y,theta
  std::string robot_path;
  std::vector<Eigen::Vector2d> robot_route;  // world frame
  double robot_route_speed = 0.6;            // m/s (the simulator's route_speed)
  std::uint64_t seed = 1;
  double scan_rate = 10.0;     // Hz
  double start = 0.0;          // s after the first annotation
  double duration = 0.0;       // s, 0 = whole file
  std::string model;           // classifier file; empty = shipped leg_adaboost_arras14.yml
  TrackerParams tracker{};
  bool track_aware_pairing = true;  // legs paired with the tracks (updateLegs); false: detector's pairing (update)
  // Diagnostic: the tracker gets the counted people's true positions plus oracle_sigma noise instead of the
  // detector's legs (updateLegs with no legs and the positions as another source, so occlusion and free space are
  // still read from the scan), which separates tracking errors from detection and leg-pairing errors.
  bool oracle_detections = false;
  double oracle_sigma = 0.05;  // m
  CameraModel camera{};        // fov > 0: its detections are fused with the laser's (PeopleTracker::updateLegs)
  DetectorParams detector{};
  MotionEvidenceParams motion{};  // scan history for the detector's motion evidence (window 0: none)
  LaserModel laser{};          // runBench sets a 360 deg scan of laser_beams beams unless laser_fov_set
  bool laser_fov_set = false;
  int laser_beams = 1080;      // 0.333 deg (`--beams`; 720 = 0.5 deg, SICK S300 class; 1440 = 0.25 deg)
  double sensor_range = 8.0;   // m, people farther away do not count (Yuan's 8 m field)
  int min_visible_beams = 3;   // line of sight: at least this many beams hit the person's legs
  double match_threshold = 0.5;
  std::string dump_dir;        // if set: groundtruth.csv and tracks.csv (t,id,x,y); dontcare.csv (t,x,y: people
                                // present but not counted); matches.csv (the scorer's correspondences:
                                // t,person,track,switched_from); robot.csv (t,x,y,theta: the sensor pose);
                                // legs.csv, tracker_state.csv (debug)
};

struct BenchRun {
  MotMetrics mot;
  HotaMetrics hota;   // similarity reaches 0 at 2 x match_threshold (alpha 0.5 = the CLEAR MOT threshold)
  IdF1::Result id;    // match_threshold
  double ospa = 0.0;  // mean OSPA, m (cut-off 2 x match_threshold, order 1)
  double process_seconds = 0.0;  // detection + tracking CPU time (wall clock of the processing only)
  [[nodiscard]] double scansPerSecond(std::size_t scans) const {
    return process_seconds > 0 ? double(scans) / process_seconds : 0.0;
  }
};

struct BenchResult {
  std::string format;
  std::size_t scans = 0;
  double duration = 0.0;
  std::size_t people_in_file = 0;
  double mean_people_counted = 0.0;
  std::vector<IdExchange> id_exchanges_fixed;  // with BenchParams::fix_id_exchanges
  BenchRun cairn, baseline;
};

// Throws InputError for unsupported worlds, unreadable files or bad robot paths.
BenchResult runBench(const BenchParams& params);
std::string benchJson(const BenchParams& params, const BenchResult& result);

}  // namespace cairn::people_tracking
