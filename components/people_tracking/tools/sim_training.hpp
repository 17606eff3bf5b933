// Training data for the leg classifiers from the simulator (components/sim, core only, no DDS): walkers with two
// legs and gait, worlds with table/chair legs, doors, walls and clutter boxes. Every simulated scan is segmented
// exactly as the detector does it, and each cluster is labelled from the simulator's ground truth (the true laser
// pose and the true leg circles / furniture / door / wall geometry at the scan's time). Tool-side library: the
// people_tracking core does not depend on the simulator.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "cairn/people_tracking/classifier.hpp"
#include "cairn/people_tracking/scan.hpp"
#include "cairn/people_tracking/scene.hpp"
#include "cairn/people_tracking/segmentation.hpp"
#include "cairn/sim/simulator.hpp"

namespace cairn::people_tracking {

/// The simulator's scan as the people pipeline's LaserScan (+inf / NaN stay "no return").
LaserScan fromSimScan(const sim::LaserScan& scan);

/// A simulator world's laser-visible geometry at time t, appended to a people_tracking scene (for `cairn people
/// bench --world <sim world>`): walls, door panels and furniture outlines as segments, furniture legs and markers
/// as circles. Only geometry is needed there (the bench counts beams on walkers), so segments are kWall and
/// circles kTableLeg regardless of what they are.
void addWorldGeometry(const sim::World& world, double t, Scene& scene);

struct SimLabelParams {
  double surface_tolerance = 0.05;  ///< m, a return within this of an object's surface belongs to it
  double positive_share = 0.7;      ///< share of a cluster's returns on person legs for a positive label
  double negative_share = 0.1;      ///< at most this share on person legs for a negative label (else ambiguous)
  double max_range = 10.0;          ///< m, clusters farther away are not labelled (the detector ignores them)
};

struct SimLabelledCluster {
  LabelledCluster sample;
  Eigen::Vector2d world_centroid = Eigen::Vector2d::Zero();  ///< cluster centroid in the world (map) frame
  int person = -1;                                           ///< simulator person id of a positive
};

struct SimLabelStats {
  std::size_t scans = 0, positives = 0, negatives = 0, ambiguous = 0, far = 0;
};

/// Labels the clusters of one simulated scan. `laser_pose` is the true laser pose in the world when the scan was
/// taken, `people` the simulator's people at that time, `t` the time for doors and furniture schedules.
std::vector<SimLabelledCluster> labelSimScan(const sim::LaserScan& scan, const sim::Pose2& laser_pose,
                                             const std::vector<sim::PersonState>& people, const sim::World& world,
                                             double t, const SegmentationParams& segmentation,
                                             const SimLabelParams& params, SimLabelStats* stats = nullptr);

struct SimTrainingParams {
  /// World names or YAML paths, one drawn per episode; "open" is a built-in empty 30 m walled hall.
  std::vector<std::string> worlds{"apartment", "office", "warehouse"};
  int episodes = 200;
  std::uint64_t seed = 1;  ///< episode k uses the stream (seed, k): disjoint seeds give disjoint data
  int scans_per_episode = 6;
  double scan_spacing = 0.5;  ///< s between labelled scans of an episode (decorrelates them)
  double warmup = 1.0;        ///< s of walking before the first labelled scan
  int min_walkers = 1, max_walkers = 6;
  double walker_area = 5.0;   ///< m, walker waypoints are drawn within this half-width around the robot
  int max_extra_tables = 2, max_extra_chairs = 6, max_extra_boxes = 4;  ///< random furniture added per episode
  std::vector<double> resolutions_deg{0.25, 1.0 / 3.0, 0.5};  ///< laser resolution drawn per episode (360° laser)
  double noise_sigma = 0.01, dropout_prob = 0.002;
  double leg_radius_min = 0.04, leg_radius_max = 0.09;        ///< m, walker leg radius drawn per episode
  double hip_half_width_min = 0.07, hip_half_width_max = 0.13;  ///< m, lateral leg offset drawn per episode
  SegmentationParams segmentation{};
  SimLabelParams label{};
};

/// Runs `episodes` short simulations (random world, robot pose and slow motion, walkers on planned paths, extra
/// furniture) and labels every cluster of the sampled scans. Deterministic in the params. Throws sim::InputError /
/// InputError for unknown worlds.
std::vector<SimLabelledCluster> simLabelledClusters(const SimTrainingParams& params, SimLabelStats* stats = nullptr);

}  // namespace cairn::people_tracking
