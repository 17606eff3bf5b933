// Continuous refinement of a scan pose on a probability grid (Hess et al. 2016 §IV-C, eq. CS): minimizes
//   Σ_k  w_occ / N · (1 − M_smooth(T·p_k))²  +  w_t² |t − t_prior|²  +  w_r² (θ − θ_prior)²
// with M_smooth the bicubic interpolation of the grid's matching values, by Levenberg–Marquardt (own
// implementation, no Ceres). The covariance is that of the scan term alone (no prior), see RefineResult.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/probability_grid.hpp"

namespace cairn::graph_slam {

struct RefineOptions {
  double occupied_weight = 1.0;      ///< w_occ (Cartographer's occupied_space_weight)
  /// Motion-prior weights. Cartographer's 2D defaults (10, 40) pin the rotation to wheel odometry: on the
  /// first 3000 ACES scans they give 0.94° mean rotational error on the short (< 10 s) relations, the same as
  /// raw odometry; w_r = 4 gives 0.35°. A weaker w_t (3) lets scans slide along the simulated office
  /// corridor (README "Front end", bench/local_slam_bench.cpp).
  double translation_weight = 10.0;  ///< w_t, 1/m (Cartographer's default)
  /// Degeneracy-aware translation prior (ours; < 0 disables, i.e. w_t in every direction): the prior uses w_t
  /// along directions the scan's point-to-line geometry constrains and this (larger) weight along directions it
  /// does not (a corridor's axis), blended by the normalized translation information (eigenvalues of the mean
  /// n·nᵀ over line-like points). A weak w_t lets good scans override bad wheel odometry (FR079); the strong one
  /// keeps scans from sliding along featureless corridors (ACES).
  double degenerate_translation_weight = -1.0;
  double rotation_weight = 4.0;      ///< w_r, 1/rad
  int max_iterations = 20;
  double step_tolerance = 1e-5;      ///< stop when |Δt| + |Δθ| is below this
  /// Covariance (pointToLineCovariance): σ of a point along its surface normal, neighbourhood for the normals.
  double point_sigma = 0.05;             ///< m (one grid cell)
  double normal_radius = 1.0;            ///< m
  int normal_neighbors = 3;              ///< points before/after in scan order considered as neighbours
  double max_planarity = 0.1;            ///< λ_min/λ_max of the neighbourhood above this: no normal
  /// Covariance floor: standard deviations added in quadrature (keeps it from being over-confident).
  double min_sigma_translation = 0.005;  ///< m
  double min_sigma_rotation = 0.002;     ///< rad
  /// Covariance cap for directions the scan does not constrain (featureless corridor axis).
  double max_sigma_translation = 10.0;   ///< m
  double max_sigma_rotation = 3.14;      ///< rad
};

struct RefineResult {
  Pose2 pose;
  /// Covariance of (x, y, θ) of the scan alone (no motion prior): pointToLineCovariance() at the result.
  /// Larger along directions the scan does not constrain (corridor axis).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double cost = 0;     ///< final total cost
  double score = 0;    ///< mean bicubic matching value of the points at the final pose
  int iterations = 0;
  bool converged = false;
};

/// Covariance of a scan alignment at `pose` (grid frame) from the scan's geometry: points in scan order (as
/// toRangeData() and the voxel filters keep them); every point with a line-like neighbourhood constrains the
/// pose along its normal with σ = o.point_sigma (point-to-line information, Censi 2007):
/// cov = (Σ JᵀJ / σ² + C_max⁻¹)⁻¹ + C_min with J = nᵀ [I, dR/dθ p]; C_max/C_min from the max/min sigmas.
/// The grid's own gradients are not used: the sampling texture of a wall would make them look informative
/// along it.
Eigen::Matrix3d pointToLineCovariance(const std::vector<Eigen::Vector2d>& pts, const Pose2& pose, const RefineOptions& o);

/// The point-to-line information Σ JᵀJ (σ = 1) of the points at `pose` and the number of line-like points that
/// contributed (pointToLineCovariance() is built from it).
Eigen::Matrix3d pointToLineInformation(const std::vector<Eigen::Vector2d>& pts, const Pose2& pose, const RefineOptions& o,
                                       int* lines = nullptr);

/// Refines `initial` (pose of the points' frame in the grid frame) towards the grid, pulled towards `prior`.
/// With no points it returns the prior, converged = false.
RefineResult refine(const ProbabilityGrid& g, const std::vector<Eigen::Vector2d>& pts, const Pose2& initial,
                    const Pose2& prior, const RefineOptions& o);

}  // namespace cairn::graph_slam
