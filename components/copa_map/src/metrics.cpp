#include "cairn/copa_map/metrics.hpp"

#include <cmath>
#include <stdexcept>

namespace cairn::copa_map {

double nrmse(const Eigen::VectorXd& pred, const Eigen::VectorXd& truth) {
  if (pred.size() != truth.size() || truth.size() == 0) throw std::invalid_argument("nrmse: size mismatch or empty");
  const double ybar = truth.mean();
  return std::sqrt((pred - truth).squaredNorm() / (ybar * ybar * static_cast<double>(truth.size())));  // eq. 4.20
}

double chiSquareDistance(const Eigen::VectorXd& pred, const Eigen::VectorXd& truth) {
  if (pred.size() != truth.size()) throw std::invalid_argument("chiSquareDistance: size mismatch");
  double s = 0;
  for (Eigen::Index i = 0; i < pred.size(); ++i) {
    const double den = pred[i] + truth[i];
    if (den > 0) s += (pred[i] - truth[i]) * (pred[i] - truth[i]) / den;  // eq. 4.21
  }
  return s;
}

double nlpd(const Eigen::VectorXd& log_density) { return -log_density.mean(); }

double coverage95(const Eigen::VectorXd& mean, const Eigen::VectorXd& std, const Eigen::VectorXd& truth) {
  if (mean.size() != truth.size() || std.size() != truth.size()) throw std::invalid_argument("coverage95: size mismatch");
  return ((mean - truth).array().abs() <= 1.96 * std.array()).cast<double>().mean();
}

}  // namespace cairn::copa_map
