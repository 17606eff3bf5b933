#include "cairn/people_tracking/masking.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cairn::people_tracking {

double personRadius(double leg_separation, const MaskParams& params) {
  if (!(leg_separation > 0.0)) return std::max(params.min_radius, params.default_radius);
  return std::max(params.min_radius, 0.5 * leg_separation + params.leg_radius + params.margin);
}

MaskMode parseMaskMode(const std::string& value, const std::string& key) {
  if (value == "tangents") return MaskMode::kTangents;
  if (value == "inside") return MaskMode::kReturnsInside;
  throw InputError(key + " must be tangents or inside, got '" + value + "'");
}

std::size_t maskScan(LaserScan& scan, const std::vector<MaskCircle>& circles, MaskMode mode) {
  validateScan(scan);
  std::size_t masked = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const auto& c : circles) {
    const double d = c.center.norm();
    // Tangent half-angle. A sensor inside the circle: "inside" looks at every beam (only returns inside the circle
    // are masked, which is exact); "tangents" masks the half plane towards the centre (masking all would blank the
    // scan).
    const double half = d > c.radius ? std::asin(c.radius / d) : (mode == MaskMode::kReturnsInside ? M_PI : M_PI / 2);
    const double bearing = std::atan2(c.center.y(), c.center.x());
    for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
      const double diff = std::remainder(scan.angle(i) - bearing, 2.0 * M_PI);
      if (std::abs(diff) > half || std::isnan(scan.ranges[i])) continue;
      if (mode == MaskMode::kReturnsInside &&
          (!scan.valid(i) || (scan.point(i) - c.center).squaredNorm() > c.radius * c.radius))
        continue;
      scan.ranges[i] = nan;
      ++masked;
    }
  }
  return masked;
}

}  // namespace cairn::people_tracking
