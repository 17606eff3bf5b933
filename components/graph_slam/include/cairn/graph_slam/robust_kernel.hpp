// Robust kernels rho(s) applied to the squared Mahalanobis error s = e^T Omega e of a factor. The optimizer
// minimizes sum rho(s) with iteratively reweighted normal equations (weight rho'(s)), as g2o does.
#pragma once

#include <string>
#include <string_view>

namespace cairn::graph_slam {

struct RobustKernel {
  enum class Type { kNone, kHuber, kCauchy, kGemanMcClure, kDcs };
  Type type = Type::kNone;
  /// Huber / Cauchy / Geman-McClure: delta in units of the error norm sqrt(s) (g2o convention).
  /// DCS: Phi in units of s (Agarwal et al., ICRA 2013).
  double delta = 1.0;

  /// rho(s) and rho'(s).
  void evaluate(double s, double& rho, double& drho) const;
  bool active() const { return type != Type::kNone; }

  /// Parses "none", "huber:1.0", "cauchy:2", "gm:1", "geman_mcclure:1", "dcs:1"; throws std::invalid_argument.
  static RobustKernel parse(std::string_view text);
  std::string toString() const;
};

}  // namespace cairn::graph_slam
