#include "cairn/graph_slam/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cairn::graph_slam {

double normalizeAngle(double a) {
  if (a > -std::numbers::pi && a <= std::numbers::pi) return a;
  a = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
  if (a <= 0.0) a += 2.0 * std::numbers::pi;
  return a - std::numbers::pi;
}

Eigen::Matrix2d rotation2(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix2d r;
  r << c, -s, s, c;
  return r;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Pose2 compose(const Pose2& a, const Pose2& b) {
  return Pose2{a.t + rotation2(a.theta) * b.t, normalizeAngle(a.theta + b.theta)};
}

Pose2 inverse(const Pose2& a) {
  return Pose2{-(rotation2(a.theta).transpose() * a.t), normalizeAngle(-a.theta)};
}

namespace {
// a * (s * (a^-1 * b)): b's motion from a, scaled by s (s in [0, 1] interpolates, s > 1 continues it).
Pose2 scaledMotion(const Pose2& a, const Pose2& b, double s) {
  const Pose2 d = compose(inverse(a), b);
  return compose(a, Pose2{s * d.t, normalizeAngle(s * d.theta)});
}
}  // namespace

std::optional<Pose2> poseAt(const std::deque<StampedPose2>& samples, double t, double tolerance) {
  if (samples.empty() || !std::isfinite(t)) return std::nullopt;
  const auto it = std::lower_bound(samples.begin(), samples.end(), t,
                                   [](const StampedPose2& s, double x) { return s.stamp < x; });
  if (it == samples.end()) {
    const StampedPose2& last = samples.back();
    if (t - last.stamp > tolerance) return std::nullopt;
    constexpr double kMinBase = 0.05, kMaxBase = 1.0;  // s: the motion continued is that over this span
    for (auto b = samples.rbegin() + 1; b != samples.rend() && last.stamp - b->stamp <= kMaxBase; ++b)
      if (last.stamp - b->stamp >= kMinBase)
        return scaledMotion(b->pose, last.pose, (t - b->stamp) / (last.stamp - b->stamp));
    return last.pose;
  }
  if (it == samples.begin()) {
    if (it->stamp - t > tolerance) return std::nullopt;
    return it->pose;
  }
  const StampedPose2& a = *(it - 1);
  return scaledMotion(a.pose, it->pose, (t - a.stamp) / std::max(1e-9, it->stamp - a.stamp));
}

Pose3 compose(const Pose3& a, const Pose3& b) {
  Pose3 r;
  r.t = a.t + a.q * b.t;
  r.q = (a.q * b.q).normalized();
  return r;
}

Pose3 inverse(const Pose3& a) {
  Pose3 r;
  r.q = a.q.conjugate();
  r.t = -(r.q * a.t);
  return r;
}

Eigen::Quaterniond expSO3(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  double real, imag_factor;
  if (theta < 1e-8) {
    // Taylor expansion: cos(x/2) ~ 1 - x^2/8, sin(x/2)/x ~ 1/2 - x^2/48.
    real = 1.0 - theta2 / 8.0;
    imag_factor = 0.5 - theta2 / 48.0;
  } else {
    real = std::cos(0.5 * theta);
    imag_factor = std::sin(0.5 * theta) / theta;
  }
  Eigen::Quaterniond q(real, imag_factor * w.x(), imag_factor * w.y(), imag_factor * w.z());
  return q.normalized();
}

Eigen::Vector3d logSO3(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  if (n < 1e-10) return 2.0 * q.vec() / q.w();
  const double angle = 2.0 * std::atan2(n, q.w());
  return angle / n * q.vec();
}

Pose2 retract(const Pose2& x, const Eigen::Vector3d& delta) {
  return Pose2{x.t + delta.head<2>(), normalizeAngle(x.theta + delta.z())};
}

Pose3 retract(const Pose3& x, const Vector6d& delta) {
  Pose3 r;
  r.t = x.t + x.q * delta.head<3>();
  r.q = (x.q * expSO3(delta.tail<3>())).normalized();
  return r;
}

}  // namespace cairn::graph_slam
