// Error functions of the pose-graph factors with analytic Jacobians (Stüde §3.1.1, eq. 3.3:
// e_ij = pi(Z_ij^-1 * X_i^-1 * X_j)). The error conventions are g2o's, so that chi^2 = sum e^T Omega e
// (Stüde eq. 3.4) equals what g2o reports for the same file:
//   SE2: e = [dx, dy, dtheta] of Z^-1 * (Xi^-1 * Xj), dtheta wrapped into (-pi, pi];
//   SE3: e = [translation; vector part of the normalized quaternion with w >= 0] of Z^-1 * (Xi^-1 * Xj).
// Jacobians are w.r.t. the manifold updates of geometry.hpp (SE2 additive, SE3 right perturbation
// [dt; dw]); passing nullptr skips a Jacobian.
#pragma once

#include "cairn/graph_slam/geometry.hpp"

namespace cairn::graph_slam {

/// Relative SE2 pose factor.
Eigen::Vector3d errorBetween2(const Pose2& xi, const Pose2& xj, const Pose2& z, Eigen::Matrix3d* jac_i,
                              Eigen::Matrix3d* jac_j);
/// The same with cos/sin of xi.theta (ci, si) and of z.theta (cz, sz) supplied by the caller: the optimizer
/// computes them once per state and once per factor instead of per factor and evaluation (same values, so
/// the result is bit-identical to the overload above).
Eigen::Vector3d errorBetween2(const Pose2& xi, const Pose2& xj, const Pose2& z, double ci, double si, double cz,
                              double sz, Eigen::Matrix3d* jac_i, Eigen::Matrix3d* jac_j);
/// Relative SE3 pose factor.
Vector6d errorBetween3(const Pose3& xi, const Pose3& xj, const Pose3& z, Matrix6d* jac_i, Matrix6d* jac_j);
/// Pose priors: the relative factor with Xi = identity, e = pi(Z^-1 * X).
Eigen::Vector3d errorPrior2(const Pose2& x, const Pose2& z, Eigen::Matrix3d* jac);
Vector6d errorPrior3(const Pose3& x, const Pose3& z, Matrix6d* jac);
/// Pose-point "xy" factors (g2o EdgeSE2PointXY): e = R^T (p - t) - z, the point in the pose frame.
Eigen::Vector2d errorPose2Point2(const Pose2& x, const Eigen::Vector2d& p, const Eigen::Vector2d& z,
                                 Eigen::Matrix<double, 2, 3>* jac_x, Eigen::Matrix2d* jac_p);
Eigen::Vector3d errorPose3Point3(const Pose3& x, const Eigen::Vector3d& p, const Eigen::Vector3d& z,
                                 Eigen::Matrix<double, 3, 6>* jac_x, Eigen::Matrix3d* jac_p);

}  // namespace cairn::graph_slam
