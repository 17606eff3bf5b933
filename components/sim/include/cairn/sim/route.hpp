// Scripted-route mode: drives the robot along waypoints using the ground-truth pose (for tests, for
// CoPA-Map's simulated observation routes — Stüde §4.3.1: manually defined trajectories at about
// 0.5 m/s with stationary intermediate stops — and as a stand-in NavigateTo until navigation exists).
// Turn-in-place when the heading error is large, otherwise a proportional arc controller.
#pragma once

#include <vector>

#include "cairn/sim/types.hpp"

namespace cairn::sim {

struct RouteConfig {
  double speed = 0.6;             ///< m/s cruise speed
  double max_w = 1.2;             ///< rad/s
  double k_heading = 2.0;         ///< angular gain
  double turn_in_place = 0.6;     ///< rad: above this heading error, rotate in place
  double tolerance = 0.15;        ///< m: waypoint reached
  double dwell = 0.0;             ///< s: stationary stop at every waypoint (the robot stops there first)
  bool loop = false;
};

class RouteFollower {
 public:
  RouteFollower(std::vector<Vec2> waypoints, RouteConfig config = {});
  /// Velocity command for the robot at ground-truth pose `pose` at sim time `now`; zero while dwelling
  /// and once the route is done.
  Twist2 command(const Pose2& pose, double now = 0.0);
  bool done() const { return done_; }
  std::size_t nextWaypoint() const { return next_; }
  const std::vector<Vec2>& waypoints() const { return waypoints_; }

 private:
  std::vector<Vec2> waypoints_;
  RouteConfig config_;
  std::size_t next_ = 0;
  bool done_ = false;
  double dwell_until_ = -1.0;
};

}  // namespace cairn::sim
