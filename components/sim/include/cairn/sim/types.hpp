// Plain value types of the simulator core. They mirror the ROS message fields they will be converted to
// (geometry_msgs/Pose2D, geometry_msgs/Twist, sensor_msgs/LaserScan, nav_msgs/Odometry) but have no
// dependency on the runtime. Units: metres, radians, seconds.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace cairn::sim {

struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(Vec2 a) { return std::hypot(a.x, a.y); }

/// Planar pose (x, y, yaw). Angles are kept in (-pi, pi].
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

/// Wraps an angle to (-pi, pi].
double normalizeAngle(double a);
/// a ⊕ b: b expressed in a's frame, returned in a's parent frame.
Pose2 compose(const Pose2& a, const Pose2& b);
/// Point p given in frame `pose` expressed in the parent frame.
Vec2 transformPoint(const Pose2& pose, Vec2 p);
/// a⁻¹ ⊕ b: b expressed in the frame of a.
Pose2 between(const Pose2& a, const Pose2& b);

/// Body velocity: v = linear.x (m/s), w = angular.z (rad/s) of geometry_msgs/Twist.
struct Twist2 {
  double v = 0.0;
  double w = 0.0;
};

/// Field meanings are those of sensor_msgs/LaserScan. Beams without a return within range_max are
/// +infinity (REP 117). Beam i points at angle_min + i * angle_increment in the laser frame.
struct LaserScan {
  double stamp = 0.0;  ///< seconds (sim time) of the first beam
  std::string frame_id = "laser";
  float angle_min = 0.0F;
  float angle_max = 0.0F;
  float angle_increment = 0.0F;
  float time_increment = 0.0F;
  float scan_time = 0.0F;
  float range_min = 0.0F;
  float range_max = 0.0F;
  std::vector<float> ranges;
  std::vector<float> intensities;
};

/// nav_msgs/Odometry: pose of child_frame_id in frame_id, twist in child_frame_id.
struct Odometry {
  double stamp = 0.0;
  std::string frame_id = "odom";
  std::string child_frame_id = "base_link";
  Pose2 pose;
  Twist2 twist;
};

/// Ground truth of one simulated person at one instant (for tracking evaluation).
struct PersonState {
  int id = 0;
  Vec2 position;       ///< centre between the legs (world frame)
  double heading = 0;  ///< walking direction
  Vec2 velocity;
  Vec2 legs[2];        ///< leg circle centres (world frame)
  double leg_radius = 0.06;
};

/// One line segment of the geometry with its surface reflectivity in [0, 1] (1 = retro-reflective).
struct Segment {
  Vec2 a;
  Vec2 b;
  float reflectivity = 0.3F;
};

/// A circle obstacle (table or chair leg, person leg, pillar, reflector post).
struct Circle {
  Vec2 center;
  double radius = 0.0;
  float reflectivity = 0.3F;
};

}  // namespace cairn::sim
