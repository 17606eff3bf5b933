#include "cairn/people_tracking/scan.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace cairn::people_tracking {

bool LaserScan::valid(std::size_t i) const {
  const float r = ranges[i];
  return std::isfinite(r) && r >= range_min && r <= range_max;
}

bool LaserScan::fullCircle() const {
  return std::abs(angle_increment) * static_cast<double>(ranges.size()) >= 2.0 * M_PI - 1e-6;
}

Eigen::Vector2d LaserScan::point(std::size_t i) const {
  const double a = angle(i);
  const double r = ranges[i];
  return {r * std::cos(a), r * std::sin(a)};
}

void validateScan(const LaserScan& scan) {
  if (scan.ranges.empty()) throw InputError("scan has no ranges");
  if (!std::isfinite(scan.angle_min) || !std::isfinite(scan.angle_increment) || scan.angle_increment == 0.0)
    throw InputError("scan angle_min/angle_increment are not finite or the increment is zero");
  const double span = std::abs(scan.angle_increment) * static_cast<double>(scan.ranges.size() - 1);
  if (span > 2.0 * M_PI + 1e-6)
    throw InputError("scan angle metadata spans more than 2*pi (" + std::to_string(span) + " rad for " +
                     std::to_string(scan.ranges.size()) + " beams)");
  if (!std::isfinite(scan.range_min) || !std::isfinite(scan.range_max) || scan.range_min < 0.0 ||
      scan.range_min >= scan.range_max)
    throw InputError("scan range_min/range_max invalid");
  if (!std::isfinite(scan.stamp)) throw InputError("scan stamp is not finite");
}

Eigen::Matrix2d Pose2::rotation() const { return Eigen::Rotation2Dd(theta).toRotationMatrix(); }

Eigen::Vector2d Pose2::transform(const Eigen::Vector2d& p) const { return rotation() * p + Eigen::Vector2d(x, y); }

Eigen::Vector2d Pose2::inverseTransform(const Eigen::Vector2d& p) const {
  return rotation().transpose() * (p - Eigen::Vector2d(x, y));
}

Pose2 Pose2::operator*(const Pose2& local) const {
  const Eigen::Vector2d p = transform({local.x, local.y});
  return Pose2{p.x(), p.y(), theta + local.theta};
}

Pose2 Pose2::inverse() const {
  const Eigen::Vector2d p = inverseTransform(Eigen::Vector2d::Zero());
  return Pose2{p.x(), p.y(), -theta};
}

}  // namespace cairn::people_tracking
