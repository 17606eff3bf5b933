// Conversions between the simulator core's plain structs (cairn/sim/types.hpp) and the runtime's messages.
// Used by the Simulator and LogPlayer components only (component/ is the runtime adapter).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "builtin_interfaces/msg/Time.hpp"
#include "cairn/sim/types.hpp"
#include "geometry_msgs/msg/TransformStamped.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "rosgraph_msgs/msg/Clock.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"

#include "cairn/msg_conversions.hpp"

namespace cairn_sim::convert {

/// Seconds (sim or log time, >= 0) -> builtin_interfaces/Time, rounded to the nanosecond.
inline builtin_interfaces::msg::Time toTime(double s) { return cairn::time_from_seconds(s); }

inline geometry_msgs::msg::Quaternion yawToQuaternion(double yaw) { return cairn::quaternion_from_yaw(yaw); }

inline sensor_msgs::msg::LaserScan toMsg(const cairn::sim::LaserScan& s, const std::string& frame_id) {
  sensor_msgs::msg::LaserScan m;
  m.header.stamp = toTime(s.stamp);
  m.header.frame_id = frame_id;
  m.angle_min = s.angle_min;
  m.angle_max = s.angle_max;
  m.angle_increment = s.angle_increment;
  m.time_increment = s.time_increment;
  m.scan_time = s.scan_time;
  m.range_min = s.range_min;
  m.range_max = s.range_max;
  m.ranges = s.ranges;
  m.intensities = s.intensities;
  return m;
}

/// nav_msgs/Odometry: pose of `child` in `frame`, twist (v, w) in `child` (REP 105).
inline nav_msgs::msg::Odometry toMsg(double stamp, const cairn::sim::Pose2& pose, const cairn::sim::Twist2& twist,
                                     const std::string& frame, const std::string& child) {
  nav_msgs::msg::Odometry m;
  m.header.stamp = toTime(stamp);
  m.header.frame_id = frame;
  m.child_frame_id = child;
  m.pose.pose.position.x = pose.x;
  m.pose.pose.position.y = pose.y;
  m.pose.pose.orientation = yawToQuaternion(pose.theta);
  m.twist.twist.linear.x = twist.v;
  m.twist.twist.angular.z = twist.w;
  return m;
}

inline geometry_msgs::msg::TransformStamped toTransform(double stamp, const cairn::sim::Pose2& pose,
                                                       const std::string& parent, const std::string& child) {
  geometry_msgs::msg::TransformStamped t;
  t.header.stamp = toTime(stamp);
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = pose.x;
  t.transform.translation.y = pose.y;
  t.transform.rotation = yawToQuaternion(pose.theta);
  return t;
}

inline rosgraph_msgs::msg::Clock toClock(double s) {
  rosgraph_msgs::msg::Clock c;
  c.clock = toTime(s);
  return c;
}

}  // namespace cairn_sim::convert
