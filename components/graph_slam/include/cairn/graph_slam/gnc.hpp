// Graduated non-convexity (GNC) with the Geman-McClure surrogate for pose graphs with false loop closures
// (Yang, Antonante, Tzoumas, Carlone, "Graduated Non-Convexity for Robust Spatial Perception", RA-L 2020).
// The outer loop re-weights the selected factors (PoseGraph::setFactorWeight) and re-optimizes warm-started
// with one Optimizer, so the symbolic factorization is shared by all outer iterations.
#pragma once

#include <cstddef>
#include <vector>

#include "cairn/graph_slam/optimizer.hpp"

namespace cairn::graph_slam {

/// GNC surrogate (Yang et al. 2020 §IV): Geman-McClure (mu decreases from a large value to 1) or truncated
/// least squares (mu increases from a small value until the weights are binary).
enum class GncSurrogate { kGemanMcClure, kTruncatedLeastSquares };

struct GncOptions {
  GncSurrogate surrogate = GncSurrogate::kGemanMcClure;
  /// true: the continuation starts from the least-squares solution (Yang et al.); false: from the graph's
  /// current values (e.g. odometry or chordal initialization), mu_0 computed from their residuals.
  bool start_from_least_squares = true;
  /// Inlier threshold c^2 on e^T Omega e; <= 0 picks the 99% chi-square quantile of the factor's dimension.
  double inlier_threshold = 0.0;
  /// mu is divided (GM) / multiplied (TLS) by this factor every outer iteration (Yang et al. use 1.4).
  double mu_step = 1.4;
  int max_outer_iterations = 100;
  /// true: only relative-pose factors between non-consecutive ids (loop closures) are re-weighted;
  /// false: every factor.
  bool loop_closures_only = true;
  /// Function tolerance of the inner optimizations while mu > 1 (the final ones use the optimizer's own).
  double inner_function_tolerance = 1e-6;
};

struct GncSummary {
  OptimizerSummary last;          ///< summary of the last inner optimization
  int outer_iterations = 0;
  int inner_iterations = 0;       ///< sum over all inner optimizations
  std::size_t rejected = 0;       ///< factors whose final weight is < 0.5
  double time_s = 0.0;
  std::vector<double> weights;    ///< final weight per factor (1 for factors not re-weighted)
};

/// Runs GNC-Geman-McClure; leaves the final weights in the graph's factors.
GncSummary optimizeGnc(PoseGraph& graph, Optimizer& optimizer, const GncOptions& options = {});

}  // namespace cairn::graph_slam
