// SE(2) / SE(3) value types and the few Lie-group operations the pose-graph optimizer needs.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <deque>
#include <optional>

namespace cairn::graph_slam {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Planar pose: translation t and heading theta (radians, kept in (-pi, pi]).
struct Pose2 {
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  double theta = 0.0;
};

/// Spatial pose: translation t and unit quaternion q (rotation body -> world).
struct Pose3 {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

/// Wraps an angle into (-pi, pi].
double normalizeAngle(double a);
Eigen::Matrix2d rotation2(double theta);
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

Pose2 compose(const Pose2& a, const Pose2& b);  ///< a * b
Pose2 inverse(const Pose2& a);
Pose3 compose(const Pose3& a, const Pose3& b);  ///< a * b
Pose3 inverse(const Pose3& a);

/// A timestamped planar pose (an odometry sample).
struct StampedPose2 {
  double stamp = 0.0;  // s
  Pose2 pose;
};
/// The pose at time t from samples sorted by stamp: between two samples, their relative motion scaled linearly in
/// time; up to `tolerance` s after the last sample, that motion continued from the last sample (the relative motion
/// over the last >= 0.05 s, from a sample at most 1 s older; held when there is none) — a scan that arrives before
/// the odometry of its stamp then gets the robot's pose at its stamp, not the one a period earlier; up to
/// `tolerance` s before the first sample, the first sample. std::nullopt when t is farther from the samples.
std::optional<Pose2> poseAt(const std::deque<StampedPose2>& samples, double t, double tolerance);

/// SO(3) exponential map of a rotation vector (axis * angle).
Eigen::Quaterniond expSO3(const Eigen::Vector3d& w);
/// SO(3) logarithm (rotation vector) of a unit quaternion.
Eigen::Vector3d logSO3(const Eigen::Quaterniond& q);

/// Manifold updates ("boxplus") used by the optimizer; the analytic Jacobians are taken w.r.t. these.
/// SE2: additive on (x, y, theta), theta re-wrapped.
Pose2 retract(const Pose2& x, const Eigen::Vector3d& delta);
/// SE3: right perturbation, t <- t + R * delta[0:3], R <- R * Exp(delta[3:6]).
Pose3 retract(const Pose3& x, const Vector6d& delta);

}  // namespace cairn::graph_slam
