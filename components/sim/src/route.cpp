#include "cairn/sim/route.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cairn::sim {

RouteFollower::RouteFollower(std::vector<Vec2> waypoints, RouteConfig config)
    : waypoints_(std::move(waypoints)), config_(config) {
  if (waypoints_.empty()) throw std::invalid_argument("route: no waypoints");
}

Twist2 RouteFollower::command(const Pose2& pose, double now) {
  if (now < dwell_until_) return {};
  while (!done_) {
    const Vec2 d = waypoints_[next_] - Vec2{pose.x, pose.y};
    if (norm(d) > config_.tolerance) break;
    if (++next_ >= waypoints_.size()) {
      if (config_.loop) next_ = 0;
      else done_ = true;
    }
    if (config_.dwell > 0.0 && !done_) {
      dwell_until_ = now + config_.dwell;
      return {};
    }
  }
  if (done_) return {};
  const Vec2 d = waypoints_[next_] - Vec2{pose.x, pose.y};
  const double err = normalizeAngle(std::atan2(d.y, d.x) - pose.theta);
  const double w = std::clamp(config_.k_heading * err, -config_.max_w, config_.max_w);
  if (std::abs(err) > config_.turn_in_place) return {0.0, w};
  // Slow down towards the last waypoint and towards corners (turn > turn_in_place), so that the robot
  // stops on the waypoint instead of overshooting it: the next leg then starts where it was planned
  // (matters for doorways that leave only a few centimetres on each side).
  double v = config_.speed * std::cos(err);
  bool stop_at_next = (!config_.loop && next_ + 1 == waypoints_.size()) || config_.dwell > 0.0;
  if (!stop_at_next) {
    const Vec2 after = waypoints_[(next_ + 1) % waypoints_.size()];
    const Vec2 out = after - waypoints_[next_];
    if (norm(out) > 1e-9 && std::abs(normalizeAngle(std::atan2(out.y, out.x) - std::atan2(d.y, d.x))) > config_.turn_in_place)
      stop_at_next = true;
  }
  if (stop_at_next) v = std::min(v, 0.8 * norm(d) + 0.05);
  return {std::max(0.0, v), w};
}

}  // namespace cairn::sim
