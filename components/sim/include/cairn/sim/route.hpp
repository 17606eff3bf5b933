// Scripted-route mode: drives the robot along waypoints using the ground-truth pose (for tests, for
// CoPA-Map's simulated observation routes, Stüde §4.3, and as a stand-in NavigateTo until navigation
// exists). Turn-in-place when the heading error is large, otherwise a proportional arc controller.
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
  bool loop = false;
};

class RouteFollower {
 public:
  RouteFollower(std::vector<Vec2> waypoints, RouteConfig config = {});
  /// Velocity command for the robot at ground-truth pose `pose`; zero once the route is done.
  Twist2 command(const Pose2& pose);
  bool done() const { return done_; }
  std::size_t nextWaypoint() const { return next_; }
  const std::vector<Vec2>& waypoints() const { return waypoints_; }

 private:
  std::vector<Vec2> waypoints_;
  RouteConfig config_;
  std::size_t next_ = 0;
  bool done_ = false;
};

}  // namespace cairn::sim
