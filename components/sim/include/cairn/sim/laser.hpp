// Simulated 2D laser scanner: ray casting against the static grid plus dynamic segments (doors,
// furniture) and circles (legs, markers), then range noise, outliers and intensities.
#pragma once

#include <string>
#include <vector>

#include "cairn/sim/raycast.hpp"
#include "cairn/sim/rng.hpp"
#include "cairn/sim/types.hpp"

namespace cairn::sim {

struct LaserConfig {
  std::string frame_id = "laser";
  Pose2 mount{0.20, 0.0, 0.0};          ///< base_link -> laser (matches urdf/cairn_service_robot.urdf)
  double fov = 2.0 * 3.14159265358979323846;  ///< rad; 2 pi = full circle (no duplicated beam)
  double resolution = 0.5 * 3.14159265358979323846 / 180.0;  ///< rad between beams (0.25°..1°)
  double rate = 10.0;                    ///< Hz
  double range_min = 0.05;               ///< m
  double range_max = 20.0;               ///< m
  double noise_sigma = 0.01;             ///< m, Gaussian range noise
  double outlier_prob = 0.001;           ///< per beam: uniform short reading in [range_min, true range]
  double dropout_prob = 0.0;             ///< per beam: no return (+inf)
  bool binary_intensity = false;         ///< Dörr §4.4: binary reflectivity {0, 1} instead of a value
  double intensity_scale = 1000.0;       ///< intensity = scale * reflectivity (non-binary mode)
  double binary_threshold = 0.5;         ///< reflectivity >= threshold -> 1 (binary mode)
  /// true: beam i is cast from the pose the moving robot has at stamp + i * time_increment (constant
  /// velocity over the scan), like a rotating scanner on a moving base; false: all beams from one pose.
  bool motion_distortion = false;

  /// Number of beams: fov/resolution (+1 unless the field of view is a full circle).
  int beams() const;
  double angleMin() const { return -0.5 * fov; }
  bool fullCircle() const;
  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
};

/// One instance per thread: scan() reuses an internal buffer.
class LaserSimulator {
 public:
  /// Keeps a reference to `walls`: it must outlive the simulator.
  LaserSimulator(LaserConfig config, const SegmentGrid& walls);

  /// Noise-free returns for a laser at `laser_pose` (world frame), including dynamic geometry.
  void castIdeal(const Pose2& laser_pose, const std::vector<Segment>& dynamic_segments,
                 const std::vector<Circle>& circles, std::vector<RayHit>& hits) const;
  /// Full scan for the robot at `robot_pose` (world), with noise drawn from rng.
  LaserScan scan(const Pose2& robot_pose, double stamp, const std::vector<Segment>& dynamic_segments,
                 const std::vector<Circle>& circles, Rng& rng) const;
  /// Same, reusing `out`'s buffers (no allocation once warmed up). `velocity` is the robot's body velocity,
  /// used when config().motion_distortion is set.
  void scan(const Pose2& robot_pose, double stamp, const std::vector<Segment>& dynamic_segments,
            const std::vector<Circle>& circles, Rng& rng, LaserScan& out, Twist2 velocity = {}) const;
  /// Noise-free returns with motion distortion: beam i from compose(arc(robot_pose, velocity, i dt), mount).
  void castIdealMoving(const Pose2& robot_pose, Twist2 velocity, const std::vector<Segment>& dynamic_segments,
                       const std::vector<Circle>& circles, std::vector<RayHit>& hits) const;

  const LaserConfig& config() const { return config_; }

 private:
  template <class HitFn>
  void forBeamsInInterval(double a0, double width, HitFn&& fn) const;

  LaserConfig config_;
  const SegmentGrid& walls_;
  int n_ = 0;
  std::vector<double> cos_, sin_;  ///< beam directions in the laser frame
  mutable std::vector<RayHit> hits_;
  mutable std::vector<Pose2> origins_;
};

}  // namespace cairn::sim
