#include "cairn/people_tracking/motion_evidence.hpp"

#include <cmath>

namespace cairn::people_tracking {

MotionEvidence::MotionEvidence(MotionEvidenceParams params) : params_(params) {
  if (!(params_.window >= 0.0) || !(params_.min_age >= 0.0) || !(params_.margin >= 0.0) || params_.max_scans == 0 ||
      params_.min_free_scans == 0)
    throw InputError("motion evidence: window, min_age and margin must be >= 0, max_scans and min_free_scans > 0");
}

void MotionEvidence::add(const LaserScan& scan, const Pose2& sensor_pose) {
  validateScan(scan);
  if (params_.window <= 0.0) return;
  if (!history_.empty() && !(scan.stamp > history_.back().scan.stamp)) history_.clear();
  const double span = std::abs(scan.angle_increment) * static_cast<double>(scan.ranges.size());
  history_.push_back({scan, sensor_pose, std::cos(sensor_pose.theta), std::sin(sensor_pose.theta),
                      span >= 2.0 * M_PI - 1e-6});
  // Keep what a query at the newest stamp can use (scans older than window before it are never consulted).
  while (history_.size() > params_.max_scans || history_.front().scan.stamp < scan.stamp - params_.window)
    history_.pop_front();
}

bool MotionEvidence::freeIn(const Past& past, const Eigen::Vector2d& p) const {
  const LaserScan& s = past.scan;
  const double dx = p.x() - past.pose.x, dy = p.y() - past.pose.y;
  const Eigen::Vector2d q(past.cos_theta * dx + past.sin_theta * dy, -past.sin_theta * dx + past.cos_theta * dy);
  const double r = q.norm();
  if (r < 1e-6) return false;
  const auto n = static_cast<long>(s.ranges.size());
  // Fractional beam index of the point's bearing, brought into one turn for a full-circle scan.
  double f = (std::atan2(q.y(), q.x()) - s.angle_min) / s.angle_increment;
  if (past.full_circle) {
    const double period = 2.0 * M_PI / std::abs(s.angle_increment);
    f = std::fmod(f, period);
    if (f < 0.0) f += period;
  }
  if (!(f >= 0.0)) return false;
  const long lo = static_cast<long>(std::floor(f));
  long hi = lo + 1;
  if (lo >= n) return false;
  if (hi >= n) {
    if (!past.full_circle) return false;
    hi = 0;
  }
  // Both bracketing beams end behind the point (or have no return within a range_max beyond it).
  const double behind = r + params_.margin;
  for (const long k : {lo, hi}) {
    const auto b = static_cast<std::size_t>(k);
    if (s.valid(b)) {
      if (s.ranges[b] < behind) return false;
    } else if (!(s.range_max >= behind) || std::isnan(s.ranges[b]) || s.ranges[b] < s.range_min) {
      return false;  // no return: free only if the laser would have seen something there (not a NaN or a too-close echo)
    }
  }
  return true;
}

bool MotionEvidence::seenFree(const Eigen::Vector2d& p, double stamp) const {
  std::size_t free = 0;
  for (const Past& past : history_) {
    const double age = stamp - past.scan.stamp;
    if (age < params_.min_age || age > params_.window) continue;
    if (freeIn(past, p) && ++free >= params_.min_free_scans) return true;
  }
  return false;
}

double MotionEvidence::freeFraction(const std::vector<Eigen::Vector2d>& points, double stamp,
                                    double stop_below) const {
  if (points.empty() || history_.empty()) return 0.0;
  const auto n = static_cast<double>(points.size());
  std::size_t free = 0, seen = 0;
  for (const Eigen::Vector2d& p : points) {
    if (seenFree(p, stamp)) ++free;
    ++seen;
    // Even if every remaining point were free the share would stay below stop_below.
    if (static_cast<double>(free) + (n - static_cast<double>(seen)) < stop_below * n) break;
  }
  return static_cast<double>(free) / n;
}

}  // namespace cairn::people_tracking
