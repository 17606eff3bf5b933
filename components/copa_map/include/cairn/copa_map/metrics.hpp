// Evaluation metrics of §4.3.2.
#pragma once

#include <Eigen/Dense>

namespace cairn::copa_map {

// NRMSE = sqrt(Σ(ŷ - y)² / (ȳ² n)) (eq. 4.20).
double nrmse(const Eigen::VectorXd& pred, const Eigen::VectorXd& truth);
// χ² distance = Σ (ŷ - y)² / (ŷ + y) (eq. 4.21); terms with ŷ + y = 0 contribute 0.
double chiSquareDistance(const Eigen::VectorXd& pred, const Eigen::VectorXd& truth);
// Mean negative log predictive density from per-point log densities.
double nlpd(const Eigen::VectorXd& log_density);
// Fraction of truths within mean ± 1.96 std.
double coverage95(const Eigen::VectorXd& mean, const Eigen::VectorXd& std, const Eigen::VectorXd& truth);

}  // namespace cairn::copa_map
