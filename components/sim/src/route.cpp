#include "cairn/sim/route.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cairn::sim {

RouteFollower::RouteFollower(std::vector<Vec2> waypoints, RouteConfig config)
    : waypoints_(std::move(waypoints)), config_(config) {
  if (waypoints_.empty()) throw std::invalid_argument("route: no waypoints");
}

Twist2 RouteFollower::command(const Pose2& pose) {
  while (!done_) {
    const Vec2 d = waypoints_[next_] - Vec2{pose.x, pose.y};
    if (norm(d) > config_.tolerance) break;
    if (++next_ >= waypoints_.size()) {
      if (config_.loop) next_ = 0;
      else done_ = true;
    }
  }
  if (done_) return {};
  const Vec2 d = waypoints_[next_] - Vec2{pose.x, pose.y};
  const double err = normalizeAngle(std::atan2(d.y, d.x) - pose.theta);
  const double w = std::clamp(config_.k_heading * err, -config_.max_w, config_.max_w);
  if (std::abs(err) > config_.turn_in_place) return {0.0, w};
  // slow down near the last waypoint and in tight turns
  double v = config_.speed * std::cos(err);
  if (!config_.loop && next_ + 1 == waypoints_.size()) v = std::min(v, 0.8 * norm(d) + 0.05);
  return {std::max(0.0, v), w};
}

}  // namespace cairn::sim
