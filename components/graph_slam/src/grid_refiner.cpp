// Levenberg–Marquardt refinement of a scan pose on the bicubic-interpolated grid (Hess et al. 2016 §IV-C).
#include "cairn/graph_slam/grid_refiner.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace cairn::graph_slam {
namespace {

struct Normal {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();  ///< Jᵀ r
  double cost = 0;                              ///< Σ r² of all residuals
  double scan_sq = 0;                           ///< Σ (1 − M)² (unscaled)
  double score = 0;                             ///< Σ M
};

// Evaluates the cost at x; with jac also the Gauss-Newton system (H = JᵀJ, g = Jᵀr).
void evaluate(const ProbabilityGrid& g, const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector3d& x,
              const Pose2& prior, const RefineOptions& o, const Eigen::Matrix2d& Wt, bool jac, Normal& n) {
  n = Normal{};
  const double c = std::cos(x.z()), s = std::sin(x.z());
  const double scale2 = o.occupied_weight / static_cast<double>(pts.size());
  Eigen::Vector2d grad;
  for (const auto& p : pts) {
    const Eigen::Vector2d q(c * p.x() - s * p.y() + x.x(), s * p.x() + c * p.y() + x.y());
    const double m = g.interpolate(q, jac ? &grad : nullptr);
    const double r = 1.0 - m;
    n.scan_sq += r * r;
    n.score += m;
    if (jac) {
      // d q / d theta = dR/dθ p
      const double dqx = -s * p.x() - c * p.y(), dqy = c * p.x() - s * p.y();
      const Eigen::Vector3d J(-grad.x(), -grad.y(), -(grad.x() * dqx + grad.y() * dqy));
      n.H.noalias() += scale2 * J * J.transpose();
      n.g += scale2 * J * r;
    }
  }
  n.cost = scale2 * n.scan_sq;
  const Eigen::Vector2d dt = x.head<2>() - prior.t;
  const double dth = normalizeAngle(x.z() - prior.theta);
  const double wr2 = o.rotation_weight * o.rotation_weight;
  n.cost += dt.dot(Wt * dt) + wr2 * dth * dth;
  if (jac) {
    n.H.topLeftCorner<2, 2>() += Wt;
    n.H(2, 2) += wr2;
    n.g.head<2>() += Wt * dt;
    n.g.z() += wr2 * dth;
  }
}

}  // namespace

RefineResult refine(const ProbabilityGrid& g, const std::vector<Eigen::Vector2d>& pts, const Pose2& initial,
                    const Pose2& prior, const RefineOptions& o) {
  RefineResult res;
  res.pose = initial;
  if (pts.empty() || !initial.t.allFinite() || !std::isfinite(initial.theta)) {
    res.pose = prior;
    return res;
  }
  Eigen::Vector3d x(initial.t.x(), initial.t.y(), initial.theta);
  // Translation prior weight matrix: w_t² I, or blended towards the degenerate weight along directions the
  // scan's geometry does not constrain (see RefineOptions::degenerate_translation_weight).
  const double wt2 = o.translation_weight * o.translation_weight;
  Eigen::Matrix2d Wt = wt2 * Eigen::Matrix2d::Identity();
  if (o.degenerate_translation_weight >= 0.0) {
    int lines = 0;
    const Eigen::Matrix3d info = pointToLineInformation(pts, initial, o, &lines);
    const double wd2 = o.degenerate_translation_weight * o.degenerate_translation_weight;
    Eigen::Matrix2d constrained = Eigen::Matrix2d::Zero();  // eigenvalues in [0, 1]: 1 = fully constrained
    if (lines > 0) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(info.topLeftCorner<2, 2>() / static_cast<double>(lines));
      // A direction counts as constrained in proportion to its share of the normals, saturating at 1/4 of them
      // (a room's walls split the normals about evenly between two directions).
      const Eigen::Vector2d c = (es.eigenvalues() * 4.0).cwiseMin(1.0).cwiseMax(0.0);
      constrained = es.eigenvectors() * c.asDiagonal() * es.eigenvectors().transpose();
    }
    Wt = wt2 * constrained + wd2 * (Eigen::Matrix2d::Identity() - constrained);
  }
  Normal n, trial;
  evaluate(g, pts, x, prior, o, Wt, true, n);
  // Levenberg–Marquardt with Marquardt scaling and Nielsen's damping update (as Ceres): the Gauss–Newton
  // step overshoots on this cost (the neglected term Σ r ∇²r is positive at occupancy peaks).
  double lambda = 1e-2, nu = 2.0;
  for (int it = 0; it < o.max_iterations; ++it) {
    res.iterations = it + 1;
    Eigen::Matrix3d Hd = n.H;
    Hd.diagonal() += lambda * n.H.diagonal().cwiseMax(1e-9);
    const Eigen::Vector3d step = Hd.ldlt().solve(-n.g);
    if (!step.allFinite()) break;
    Eigen::Vector3d xt = x + step;
    xt.z() = normalizeAngle(xt.z());
    evaluate(g, pts, xt, prior, o, Wt, true, trial);
    const double predicted = -(2.0 * n.g.dot(step) + step.dot(n.H * step));
    const double rho = predicted > 0.0 ? (n.cost - trial.cost) / predicted : -1.0;
    const bool small = step.head<2>().norm() + std::abs(step.z()) < o.step_tolerance;
    if (rho > 0.0) {
      x = xt;
      n = trial;
      const double t = 2.0 * rho - 1.0;
      lambda *= std::max(1.0 / 3.0, 1.0 - t * t * t);
      nu = 2.0;
    } else {
      lambda *= nu;
      nu *= 2.0;
    }
    if (small || lambda > 1e8) {  // tiny step, or no descent possible: at a minimum up to rounding
      res.converged = true;
      break;
    }
  }
  res.pose.t = x.head<2>();
  res.pose.theta = normalizeAngle(x.z());
  res.cost = n.cost;
  const double N = static_cast<double>(pts.size());
  res.score = n.score / N;
  res.covariance = pointToLineCovariance(pts, res.pose, o);
  return res;
}

Eigen::Matrix3d pointToLineInformation(const std::vector<Eigen::Vector2d>& pts, const Pose2& pose, const RefineOptions& o,
                                       int* lines) {
  // Information of a point-to-line alignment (Censi 2007 style): every point with a line-like neighbourhood
  // (neighbours within normal_radius among the normal_neighbors points before and after it in scan order)
  // constrains the pose along its surface normal n: J = nᵀ [I, dR/dθ p], Ω = Σ JᵀJ / σ².
  const double s = std::sin(pose.theta), c = std::cos(pose.theta);
  const Eigen::Matrix2d R = rotation2(pose.theta);
  const int N = static_cast<int>(pts.size());
  const double r2 = o.normal_radius * o.normal_radius;
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  int count = 0;
  for (int k = 0; k < N; ++k) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    int cnt = 0;
    const int lo = std::max(0, k - o.normal_neighbors), hi = std::min(N - 1, k + o.normal_neighbors);
    for (int j = lo; j <= hi; ++j) {
      if ((pts[static_cast<std::size_t>(j)] - pts[static_cast<std::size_t>(k)]).squaredNorm() <= r2) {
        mean += pts[static_cast<std::size_t>(j)];
        ++cnt;
      }
    }
    if (cnt < 3) continue;
    mean /= cnt;
    Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
    for (int j = lo; j <= hi; ++j) {
      const Eigen::Vector2d d = pts[static_cast<std::size_t>(j)] - mean;
      if ((pts[static_cast<std::size_t>(j)] - pts[static_cast<std::size_t>(k)]).squaredNorm() <= r2) C += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
    const Eigen::Vector2d ev = es.eigenvalues();  // ascending
    if (!(ev(1) > 0.0) || ev(0) > o.max_planarity * ev(1)) continue;  // not line-like (corner, clutter)
    const Eigen::Vector2d n = R * es.eigenvectors().col(0);
    const Eigen::Vector2d& p = pts[static_cast<std::size_t>(k)];
    const Eigen::Vector2d dq(-s * p.x() - c * p.y(), c * p.x() - s * p.y());
    const Eigen::Vector3d J(n.x(), n.y(), n.dot(dq));
    info.noalias() += J * J.transpose();
    ++count;
  }
  if (lines != nullptr) *lines = count;
  return info;
}

Eigen::Matrix3d pointToLineCovariance(const std::vector<Eigen::Vector2d>& pts, const Pose2& pose, const RefineOptions& o) {
  Eigen::Matrix3d info = pointToLineInformation(pts, pose, o);
  const double s2 = o.point_sigma * o.point_sigma;
  const Eigen::Vector3d max_var(o.max_sigma_translation * o.max_sigma_translation,
                                o.max_sigma_translation * o.max_sigma_translation,
                                o.max_sigma_rotation * o.max_sigma_rotation);
  const Eigen::Vector3d min_var(o.min_sigma_translation * o.min_sigma_translation,
                                o.min_sigma_translation * o.min_sigma_translation,
                                o.min_sigma_rotation * o.min_sigma_rotation);
  info /= s2;
  info.diagonal() += max_var.cwiseInverse();  // caps the variance of unconstrained directions
  Eigen::Matrix3d cov = info.inverse();
  cov = 0.5 * (cov + cov.transpose()).eval();
  cov.diagonal() += min_var;
  return cov;
}

}  // namespace cairn::graph_slam
