// The simulator: a world, one differential-drive robot with a laser and odometry, and people. Fixed
// physics step, laser and odometry at their own rates, all randomness from one seed (separate streams
// per subsystem), so the same seed and world give a byte-identical scan stream.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "cairn/sim/diff_drive.hpp"
#include "cairn/sim/laser.hpp"
#include "cairn/sim/people.hpp"
#include "cairn/sim/route.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

struct SimConfig {
  DiffDriveConfig robot;
  LaserConfig laser;
  OdometryNoiseConfig odometry;
  GaitConfig gait;
  SocialForceConfig social;   ///< walkers avoid each other and the robot (footprint_radius)
  double physics_dt = 0.01;   ///< s
  double odom_rate = 50.0;    ///< Hz
  std::uint64_t seed = 1;
  bool people = true;         ///< recorded / scripted people of the world
  bool crowd = true;          ///< the world's crowd model (if it has one)
  std::optional<Pose2> start; ///< overrides world.robot_start
};

/// Everything produced by one advance() call, in time order per stream.
struct SimOutput {
  std::vector<LaserScan> scans;
  std::vector<Odometry> odometry;      ///< noisy odometry (odom -> base_link)
  std::vector<Odometry> ground_truth;  ///< true pose (map -> base_link), same stamps as odometry
};

class Simulator {
 public:
  Simulator(World world, SimConfig config);
  // Subsystems keep references into the simulator (grid, world): not copyable or movable.
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  /// Velocity command (geometry_msgs/Twist on cmd_vel). Ignored while a route is active.
  void setCommand(Twist2 cmd);
  /// Drives along waypoints using ground truth (scripted-route mode).
  void followRoute(std::vector<Vec2> waypoints, RouteConfig config = {});
  void cancelRoute();
  bool routeActive() const { return route_.has_value() && !route_->done(); }

  /// Advances sim time by `duration` in physics steps; appends scans/odometry that fall due.
  void advance(double duration, SimOutput& out);

  double time() const { return t_; }
  Pose2 groundTruth() const { return robot_.pose(); }
  Odometry odometry() const;
  const std::vector<PersonState>& people() const { return people_.people(); }
  const World& world() const { return world_; }
  const SimConfig& config() const { return config_; }
  const SegmentGrid& walls() const { return grid_; }
  const DiffDrive& robot() const { return robot_; }
  /// Distance from p to the nearest obstacle the robot collides with (walls, doors, furniture).
  double obstacleClearance(Vec2 p, double max_dist) const { return clearance(p, max_dist); }
  /// Current dynamic geometry (doors, furniture, markers at time(); people's legs).
  void dynamicGeometry(std::vector<Segment>& segments, std::vector<Circle>& circles) const;

 private:
  void stepOnce(SimOutput& out);
  /// Distance from p to the nearest wall, door panel or furniture (capped at max_dist).
  double clearance(Vec2 p, double max_dist) const;

  World world_;
  SimConfig config_;
  SegmentGrid grid_;
  LaserSimulator laser_;
  DiffDrive robot_;
  OdometryModel odom_;
  PeopleSimulator people_;
  Rng laser_rng_;
  std::optional<RouteFollower> route_;
  Twist2 cmd_;
  long step_ = 0;
  double t_ = 0.0;
  long next_scan_step_ = 0, next_odom_step_ = 0;
  long scan_count_ = 0, odom_count_ = 0;
  Twist2 last_odom_twist_;
  std::vector<Segment> dyn_segments_;
  std::vector<Circle> dyn_circles_;
  mutable std::vector<Segment> collision_segments_;
  mutable std::vector<Circle> collision_circles_;
};

/// FNV-1a 64-bit digest of a scan (stamp, geometry fields, ranges and intensities as raw bytes), chained
/// with `seed` (pass the previous digest to hash a stream).
std::uint64_t scanDigest(const LaserScan& scan, std::uint64_t seed = 0xcbf29ce484222325ULL);

}  // namespace cairn::sim
