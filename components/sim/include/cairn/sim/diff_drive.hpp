// Differential-drive robot: velocity and acceleration limits, exact arc integration, optional stall on
// collision with the static walls; odometry with systematic and random error.
#pragma once

#include <cstddef>
#include <functional>

#include "cairn/sim/raycast.hpp"
#include "cairn/sim/rng.hpp"
#include "cairn/sim/types.hpp"

namespace cairn::sim {

struct DiffDriveConfig {
  double max_v = 1.0;           ///< m/s forward
  double max_v_reverse = 0.3;   ///< m/s backward
  double max_w = 1.5;           ///< rad/s
  double max_acc = 0.8;         ///< m/s² (speeding up)
  double max_dec = 1.5;         ///< m/s² (braking)
  double max_alpha = 3.0;       ///< rad/s²
  double wheel_separation = 0.46;  ///< m (urdf: wheel joints at y = ±0.23)
  double wheel_radius = 0.08;      ///< m
  double footprint_radius = 0.28;  ///< m, for collision checks
  double cmd_timeout = 0.5;        ///< s without a command -> stop (like most base drivers)
  bool stall_on_collision = true;
};

/// Odometry error model. Per increment (d, dθ) of the true motion in the robot frame:
///   d_o  = d (1 + scale_error) + N(0, sigma_trans² |d|)
///   dθ_o = dθ (1 + rotation_scale_error) + heading_drift · d + N(0, sigma_rot² |dθ| + sigma_rot_per_m² |d|)
/// Variances grow linearly with the distance travelled, so the error statistics do not depend on the
/// physics step. Defaults: 1 % systematic distance error plus 1 cm/√m random error — the order of
/// magnitude of the wheel odometry of Dörr §6.2.2 ("≈1 % of the distance").
struct OdometryNoiseConfig {
  double scale_error = 0.01;
  double rotation_scale_error = 0.0;
  double heading_drift = 0.0;     ///< rad per metre
  double sigma_trans = 0.01;      ///< m / √m
  double sigma_rot = 0.01;        ///< rad / √rad
  double sigma_rot_per_m = 0.005; ///< rad / √m
};

class DiffDrive {
 public:
  DiffDrive(DiffDriveConfig config, Pose2 start);
  /// Sets the commanded body velocity (clamped to the velocity limits) at sim time `stamp`.
  void setCommand(Twist2 cmd, double stamp);
  /// Advances by dt: the velocity approaches the command within the acceleration limits, then the pose
  /// follows the exact arc. With walls and stall_on_collision, a step that would put the footprint into
  /// a wall is not taken (velocity set to zero, stalled() true).
  void step(double dt, double now, const SegmentGrid* walls = nullptr);
  /// Distance from a point to the nearest obstacle, capped at the given maximum.
  using ClearanceFn = std::function<double(Vec2 p, double max_dist)>;
  /// Same, with any obstacle model (the simulator adds doors and furniture to the walls).
  void step(double dt, double now, const ClearanceFn& clearance);
  Pose2 pose() const { return pose_; }
  Twist2 velocity() const { return vel_; }
  Twist2 command() const { return cmd_; }
  bool stalled() const { return stalled_; }
  /// Physics steps stalled since construction (stalled() only tells the last step).
  std::size_t stallCount() const { return stall_count_; }
  void reset(Pose2 pose);
  const DiffDriveConfig& config() const { return config_; }
  /// Wheel angular velocities (left, right) in rad/s for the current body velocity.
  std::pair<double, double> wheelSpeeds() const;

 private:
  DiffDriveConfig config_;
  Pose2 pose_;
  Twist2 vel_, cmd_;
  double cmd_stamp_ = 0.0;
  bool stalled_ = false;
  std::size_t stall_count_ = 0;
};

/// Exact pose after driving with constant (v, w) for dt from p.
Pose2 integrateArc(const Pose2& p, Twist2 vel, double dt);

class OdometryModel {
 public:
  OdometryModel(OdometryNoiseConfig config, Pose2 true_start, Rng rng);
  /// Feeds the true motion from the last true pose to `true_pose`.
  void update(const Pose2& true_pose);
  Pose2 pose() const { return odom_; }
  const OdometryNoiseConfig& config() const { return config_; }

 private:
  OdometryNoiseConfig config_;
  Pose2 last_true_;
  Pose2 odom_;
  Rng rng_;
};

}  // namespace cairn::sim
