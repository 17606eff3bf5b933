// Small conversions every component adapter needs between message fields and plain numbers (header-only):
// builtin_interfaces/Time <-> seconds, planar yaw <-> geometry_msgs/Quaternion.
#ifndef CAIRN_MSG_CONVERSIONS_HPP
#define CAIRN_MSG_CONVERSIONS_HPP

#include <cmath>
#include <cstdint>

#include "builtin_interfaces/msg/Time.hpp"
#include "geometry_msgs/msg/Quaternion.hpp"

namespace cairn {

/// builtin_interfaces/Time -> seconds.
inline double to_seconds(const builtin_interfaces::msg::Time& t) { return t.sec + 1e-9 * t.nanosec; }

/// Seconds -> builtin_interfaces/Time, rounded to the nanosecond (negative or NaN -> 0).
inline builtin_interfaces::msg::Time time_from_seconds(double s) {
  builtin_interfaces::msg::Time t;
  if (!(s > 0.0)) return t;
  double sec = std::floor(s);
  double ns = std::round((s - sec) * 1e9);
  if (ns >= 1e9) {
    sec += 1.0;
    ns -= 1e9;
  }
  t.sec = static_cast<int32_t>(sec);
  t.nanosec = static_cast<uint32_t>(ns);
  return t;
}

/// Yaw (rotation about z) of a quaternion.
inline double yaw_of(const geometry_msgs::msg::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

/// Quaternion of a rotation by `yaw` about z.
inline geometry_msgs::msg::Quaternion quaternion_from_yaw(double yaw) {
  geometry_msgs::msg::Quaternion q;
  q.z = std::sin(0.5 * yaw);
  q.w = std::cos(0.5 * yaw);
  return q;
}

}  // namespace cairn

#endif  // CAIRN_MSG_CONVERSIONS_HPP
