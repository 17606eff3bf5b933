#include "cairn/people_tracking/features.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

namespace cairn::people_tracking {

const std::array<FeatureInfo, kNumFeatures>& featureRegistry() {
  static const std::array<FeatureInfo, kNumFeatures> registry{{
      {"num_points", "number of points"},
      {"std_from_centroid", "standard deviation of the points from the centroid (m)"},
      {"mean_abs_dev_median", "mean distance of the points from the component-wise median (m)"},
      {"jump_prev", "distance to the preceding valid return (m, capped)"},
      {"jump_next", "distance to the following valid return (m, capped)"},
      {"width", "distance between first and last point (m)"},
      {"linearity", "sum of squared residuals of a total-least-squares line fit (m^2)"},
      {"circularity", "sum of squared residuals of an algebraic circle fit (m^2)"},
      {"circle_radius", "radius of the fitted circle (m, clamped to 10)"},
      {"boundary_length", "polyline length through the points (m)"},
      {"boundary_regularity", "standard deviation of consecutive point distances (m)"},
      {"mean_curvature", "mean Menger curvature of consecutive point triples (1/m)"},
      {"mean_angular_difference", "mean absolute turning angle between consecutive boundary vectors (rad)"},
      {"distance", "distance of the centroid from the sensor (m)"},
  }};
  return registry;
}

namespace {
constexpr double kMaxRadius = 10.0;

std::size_t idx(Feature f) { return static_cast<std::size_t>(f); }
}  // namespace

FeatureVector computeFeatures(const Cluster& cluster) {
  FeatureVector f{};
  const auto& p = cluster.points;
  const std::size_t n = p.size();
  f[idx(Feature::kNumPoints)] = static_cast<double>(n);
  f[idx(Feature::kJumpPrev)] = cluster.jump_prev;
  f[idx(Feature::kJumpNext)] = cluster.jump_next;
  if (n == 0) return f;
  const Eigen::Vector2d c = cluster.centroid();
  f[idx(Feature::kDistance)] = c.norm();
  if (n < 2) return f;
  const double dn = static_cast<double>(n);

  double ss = 0.0;
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& q : p) {
    const Eigen::Vector2d d = q - c;
    ss += d.squaredNorm();
    scatter += d * d.transpose();
  }
  f[idx(Feature::kStdFromCentroid)] = std::sqrt(ss / (dn - 1.0));

  std::vector<double> xs(n), ys(n);
  for (std::size_t i = 0; i < n; ++i) {
    xs[i] = p[i].x();
    ys[i] = p[i].y();
  }
  auto median = [](std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<long>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    double m = *mid;
    if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), mid));
    return m;
  };
  const Eigen::Vector2d med(median(xs), median(ys));
  double mad = 0.0;
  for (const auto& q : p) mad += (q - med).norm();
  f[idx(Feature::kMeanAbsDevMedian)] = mad / dn;

  f[idx(Feature::kWidth)] = (p.front() - p.back()).norm();

  // Total least squares line: residual sum = smallest eigenvalue of the scatter matrix.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter, Eigen::EigenvaluesOnly);
  f[idx(Feature::kLinearity)] = std::max(0.0, eig.eigenvalues()(0));

  std::vector<double> seg(n - 1);
  double len = 0.0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    seg[i] = (p[i + 1] - p[i]).norm();
    len += seg[i];
  }
  f[idx(Feature::kBoundaryLength)] = len;
  const double mean_seg = len / static_cast<double>(n - 1);
  double var_seg = 0.0;
  for (double s : seg) var_seg += (s - mean_seg) * (s - mean_seg);
  f[idx(Feature::kBoundaryRegularity)] = std::sqrt(var_seg / static_cast<double>(n - 1));

  if (n < 3) return f;

  // Algebraic (Kasa) circle fit on centred coordinates: 2 a x + 2 b y + k = x^2 + y^2, r^2 = k + a^2 + b^2.
  Eigen::MatrixXd A(static_cast<long>(n), 3);
  Eigen::VectorXd b(static_cast<long>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d d = p[i] - c;
    A.row(static_cast<long>(i)) << 2.0 * d.x(), 2.0 * d.y(), 1.0;
    b(static_cast<long>(i)) = d.squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(1e-9);
  const bool collinear = qr.rank() < 3 || eig.eigenvalues()(0) <= 1e-12 * eig.eigenvalues()(1);
  const Eigen::Vector3d sol = collinear ? Eigen::Vector3d::Zero() : Eigen::Vector3d(qr.solve(b));
  const Eigen::Vector2d center(sol(0), sol(1));
  const double r2 = sol(2) + center.squaredNorm();
  double radius = (std::isfinite(r2) && r2 > 0.0) ? std::sqrt(r2) : kMaxRadius;
  double circ = 0.0;
  if (collinear || radius >= kMaxRadius || !center.allFinite()) {
    radius = kMaxRadius;
    circ = f[idx(Feature::kLinearity)];  // collinear: the circle degenerates into the line fit
  } else {
    for (const auto& q : p) {
      const double e = (q - c - center).norm() - radius;
      circ += e * e;
    }
  }
  f[idx(Feature::kCircularity)] = circ;
  f[idx(Feature::kCircleRadius)] = radius;

  double curv = 0.0;
  double ang = 0.0;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const Eigen::Vector2d u = p[i] - p[i - 1];
    const Eigen::Vector2d v = p[i + 1] - p[i];
    const double cross = u.x() * v.y() - u.y() * v.x();
    const double da = u.norm(), db = v.norm(), dc = (p[i + 1] - p[i - 1]).norm();
    const double denom = da * db * dc;
    curv += denom > 1e-12 ? 2.0 * std::abs(cross) / denom : 0.0;  // Menger curvature 4*area/(abc)
    ang += std::abs(std::atan2(cross, u.dot(v)));
  }
  f[idx(Feature::kMeanCurvature)] = curv / static_cast<double>(n - 2);
  f[idx(Feature::kMeanAngularDifference)] = ang / static_cast<double>(n - 2);
  return f;
}

std::vector<float> FeatureSet::select(const FeatureVector& all) const {
  std::vector<float> out;
  out.reserve(features.size());
  for (Feature f : features) out.push_back(static_cast<float>(all[idx(f)]));
  return out;
}

std::vector<std::string> FeatureSet::featureNames() const {
  std::vector<std::string> out;
  for (Feature f : features) out.emplace_back(featureRegistry()[idx(f)].name);
  return out;
}

FeatureSet featureSet(std::string_view key) {
  if (key == "arras14@1") {
    FeatureSet s{"arras14", 1, {}};
    for (std::size_t i = 0; i < kNumFeatures; ++i) s.features.push_back(static_cast<Feature>(i));
    return s;
  }
  if (key == "stuede5@1") {
    return FeatureSet{"stuede5",
                      1,
                      {Feature::kNumPoints, Feature::kDistance, Feature::kStdFromCentroid, Feature::kWidth,
                       Feature::kCircularity}};
  }
  throw InputError("unknown feature set '" + std::string(key) + "'");
}

std::vector<std::string> featureSetKeys() { return {"arras14@1", "stuede5@1"}; }

}  // namespace cairn::people_tracking
