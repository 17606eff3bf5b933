// TF: a buffer of timestamped transforms between coordinate frames, with interpolation and lookup
// between any two connected frames, fed from the tf / tf_static topics (tf2_msgs/TFMessage).
#ifndef CAIRN_TF_HPP
#define CAIRN_TF_HPP

#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cairn/clock.hpp"
#include "geometry_msgs/msg/TransformStamped.hpp"

namespace cairn {

class Node;
template <class T>
class Subscription;
template <class T>
class Publisher;

class TransformError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Rigid transform p_parent = q * p_child + t.
struct RigidTransform {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  RigidTransform operator*(const RigidTransform& o) const { return {t + q * o.t, (q * o.q).normalized()}; }
  RigidTransform inverse() const {
    const Eigen::Quaterniond qi = q.conjugate();
    return {-(qi * t), qi};
  }
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return q * p + t; }
  /// Linear interpolation of the translation, slerp of the rotation; s in [0, 1].
  static RigidTransform interpolate(const RigidTransform& a, const RigidTransform& b, double s);
};

RigidTransform from_msg(const geometry_msgs::msg::Transform& m);
geometry_msgs::msg::Transform to_msg(const RigidTransform& t);
inline Time stamp_of(const builtin_interfaces::msg::Time& t) { return Time{int64_t(t.sec) * 1000000000LL + t.nanosec}; }
builtin_interfaces::msg::Time to_stamp(Time t);

class TransformBuffer {
 public:
  explicit TransformBuffer(double cache_seconds = 10.0) : cache_ns_(int64_t(cache_seconds * 1e9)) {}
  /// Adds a transform (parent = header.frame_id, child = child_frame_id). Throws TransformError for empty or
  /// equal frame names, non-finite values or a zero quaternion; a child frame re-parented keeps the new parent.
  void set_transform(const geometry_msgs::msg::TransformStamped& t, bool is_static);
  /// The transform taking points in `source` to `target` at `time` (Time{0}: the latest time all links on the
  /// path have data). Throws TransformError when the frames are not connected or `time` is outside the cache.
  RigidTransform lookup(const std::string& target, const std::string& source, Time time) const;
  geometry_msgs::msg::TransformStamped lookup_msg(const std::string& target, const std::string& source, Time time) const;
  bool can_transform(const std::string& target, const std::string& source, Time time) const;
  std::vector<std::string> frames() const;

 private:
  struct Sample {
    int64_t stamp;
    RigidTransform tf;
  };
  struct Link {
    std::string parent;
    bool is_static = false;
    std::deque<Sample> samples;  // sorted by stamp
  };
  /// child -> its parent transform at time; `time` 0 -> latest.
  RigidTransform link_at(const std::string& child, const Link& l, int64_t time) const;
  std::vector<std::string> chain_to_root(const std::string& frame) const;
  int64_t cache_ns_;
  mutable std::mutex mu_;
  std::map<std::string, Link> links_;
};

/// Keeps a TransformBuffer filled from /tf and /tf_static.
class TransformListener {
 public:
  TransformListener(Node& node, std::shared_ptr<TransformBuffer> buffer);
  const std::shared_ptr<TransformBuffer>& buffer() const { return buffer_; }

 private:
  std::shared_ptr<TransformBuffer> buffer_;
  std::shared_ptr<void> tf_sub_, static_sub_;
};

}  // namespace cairn

#endif  // CAIRN_TF_HPP
