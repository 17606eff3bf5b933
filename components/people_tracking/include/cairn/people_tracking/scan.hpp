// Plain 2D laser scan with ROS sensor_msgs/LaserScan semantics, and small geometry types.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace cairn::people_tracking {

// Thrown on malformed input (bad scan metadata, time going backwards in strict APIs, corrupt model files).
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Same meaning as sensor_msgs/LaserScan: beam i has bearing angle_min + i * angle_increment (rad, sensor frame,
// x forward, y left). Ranges outside [range_min, range_max], NaN and inf are "no return".
struct LaserScan {
  double stamp = 0.0;  // seconds
  double angle_min = 0.0;
  double angle_increment = 0.0;
  double range_min = 0.0;
  double range_max = 0.0;
  std::vector<float> ranges;

  [[nodiscard]] double angle(std::size_t i) const { return angle_min + static_cast<double>(i) * angle_increment; }
  [[nodiscard]] bool valid(std::size_t i) const;
  // Beam i saw nothing within range_max: +inf (REP 117) or a finite value beyond range_max (drivers that send
  // range_max + 1). NaN (an erroneous reading) and values below range_min (too close, -inf) are not "nothing there".
  [[nodiscard]] bool beyondRange(std::size_t i) const { return ranges[i] > range_max; }
  // The beams cover the whole circle: the last beam's neighbour is the first.
  [[nodiscard]] bool fullCircle() const;
  [[nodiscard]] Eigen::Vector2d point(std::size_t i) const;
};

// Throws InputError when the metadata cannot describe a scan: empty ranges, non-finite or zero increment,
// range_min >= range_max, negative range_min, non-finite stamp. NaN/inf ranges are allowed (no return).
void validateScan(const LaserScan& scan);

// Planar pose (x, y, yaw) of the sensor/robot in the tracking frame (odom or map).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  [[nodiscard]] Eigen::Vector2d transform(const Eigen::Vector2d& p) const;         // local -> frame
  [[nodiscard]] Eigen::Vector2d inverseTransform(const Eigen::Vector2d& p) const;  // frame -> local
  [[nodiscard]] Eigen::Matrix2d rotation() const;
  // Composition: (this * local) is the pose `local` (given in this pose's frame) in this pose's parent frame.
  [[nodiscard]] Pose2 operator*(const Pose2& local) const;
  [[nodiscard]] Pose2 inverse() const;
};

}  // namespace cairn::people_tracking
