#include "cairn/tf.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "cairn/node.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

namespace cairn {

RigidTransform RigidTransform::interpolate(const RigidTransform& a, const RigidTransform& b, double s) {
  return {a.t + s * (b.t - a.t), a.q.slerp(s, b.q).normalized()};
}

RigidTransform from_msg(const geometry_msgs::msg::Transform& m) {
  return {Eigen::Vector3d(m.translation.x, m.translation.y, m.translation.z),
          Eigen::Quaterniond(m.rotation.w, m.rotation.x, m.rotation.y, m.rotation.z).normalized()};
}

geometry_msgs::msg::Transform to_msg(const RigidTransform& t) {
  geometry_msgs::msg::Transform m;
  m.translation.x = t.t.x();
  m.translation.y = t.t.y();
  m.translation.z = t.t.z();
  m.rotation.w = t.q.w();
  m.rotation.x = t.q.x();
  m.rotation.y = t.q.y();
  m.rotation.z = t.q.z();
  return m;
}

builtin_interfaces::msg::Time to_stamp(Time t) {
  builtin_interfaces::msg::Time s;
  s.sec = static_cast<int32_t>(t.ns / 1000000000LL);
  s.nanosec = static_cast<uint32_t>(t.ns % 1000000000LL);
  return s;
}

void TransformBuffer::set_transform(const geometry_msgs::msg::TransformStamped& m, bool is_static) {
  const std::string& parent = m.header.frame_id;
  const std::string& child = m.child_frame_id;
  if (parent.empty() || child.empty()) throw TransformError("transform with an empty frame name");
  if (parent == child) throw TransformError("transform from frame '" + child + "' to itself");
  const auto& tr = m.transform;
  for (double v : {tr.translation.x, tr.translation.y, tr.translation.z, tr.rotation.x, tr.rotation.y, tr.rotation.z,
                   tr.rotation.w}) {
    if (!std::isfinite(v)) throw TransformError("transform " + parent + " -> " + child + " has a non-finite value");
  }
  const double qn = std::sqrt(tr.rotation.x * tr.rotation.x + tr.rotation.y * tr.rotation.y +
                              tr.rotation.z * tr.rotation.z + tr.rotation.w * tr.rotation.w);
  if (qn < 1e-9) throw TransformError("transform " + parent + " -> " + child + " has a zero quaternion");
  const int64_t stamp = stamp_of(m.header.stamp).ns;
  std::lock_guard l(mu_);
  Link& link = links_[child];
  if (link.parent != parent || link.is_static != is_static) link.samples.clear();
  link.parent = parent;
  link.is_static = is_static;
  const Sample s{is_static ? 0 : stamp, from_msg(tr)};
  if (is_static) {
    link.samples.assign(1, s);
    return;
  }
  auto it = std::upper_bound(link.samples.begin(), link.samples.end(), stamp,
                             [](int64_t t, const Sample& x) { return t < x.stamp; });
  if (it != link.samples.begin() && std::prev(it)->stamp == stamp) {
    std::prev(it)->tf = s.tf;  // same stamp: replace
  } else {
    link.samples.insert(it, s);
  }
  while (!link.samples.empty() && link.samples.back().stamp - link.samples.front().stamp > cache_ns_) {
    link.samples.pop_front();
  }
}

RigidTransform TransformBuffer::link_at(const std::string& child, const Link& l, int64_t time) const {
  if (l.samples.empty()) throw TransformError("no data for frame '" + child + "'");
  if (l.is_static || time == 0) return l.is_static ? l.samples.front().tf : l.samples.back().tf;
  const auto& f = l.samples.front();
  const auto& b = l.samples.back();
  if (time < f.stamp || time > b.stamp) {
    throw TransformError("lookup of '" + child + "' at " + std::to_string(time * 1e-9) +
                         " s would extrapolate (data from " + std::to_string(f.stamp * 1e-9) + " to " +
                         std::to_string(b.stamp * 1e-9) + " s)");
  }
  auto hi = std::lower_bound(l.samples.begin(), l.samples.end(), time,
                             [](const Sample& x, int64_t t) { return x.stamp < t; });
  if (hi->stamp == time || hi == l.samples.begin()) return hi->tf;
  auto lo = std::prev(hi);
  const double s = double(time - lo->stamp) / double(hi->stamp - lo->stamp);
  return RigidTransform::interpolate(lo->tf, hi->tf, s);
}

std::vector<std::string> TransformBuffer::chain_to_root(const std::string& frame) const {
  std::vector<std::string> chain{frame};
  std::set<std::string> seen{frame};
  for (auto it = links_.find(frame); it != links_.end(); it = links_.find(it->second.parent)) {
    if (!seen.insert(it->second.parent).second) throw TransformError("frame loop through '" + it->second.parent + "'");
    chain.push_back(it->second.parent);
  }
  return chain;
}

RigidTransform TransformBuffer::lookup(const std::string& target, const std::string& source, Time time) const {
  std::lock_guard l(mu_);
  if (target == source) return {};
  const auto a = chain_to_root(source);
  const auto b = chain_to_root(target);
  std::string common;
  for (const auto& f : a) {
    if (std::find(b.begin(), b.end(), f) != b.end()) {
      common = f;
      break;
    }
  }
  if (common.empty()) {
    throw TransformError("frames '" + target + "' and '" + source + "' are not connected (roots '" + b.back() +
                         "' and '" + a.back() + "')");
  }
  int64_t t = time.ns;
  if (t == 0) {  // the latest time every dynamic link on the path has data for
    t = INT64_MAX;
    for (const auto* chain : {&a, &b}) {
      for (const auto& f : *chain) {
        if (f == common) break;
        const Link& lk = links_.at(f);
        if (!lk.is_static && !lk.samples.empty()) t = std::min(t, lk.samples.back().stamp);
      }
    }
    if (t == INT64_MAX) t = 0;
  }
  auto to_common = [&](const std::vector<std::string>& chain) {
    RigidTransform acc;  // T_common_frame
    std::vector<RigidTransform> parts;
    for (const auto& f : chain) {
      if (f == common) break;
      parts.push_back(link_at(f, links_.at(f), t));  // T_parent_f
    }
    for (auto it = parts.rbegin(); it != parts.rend(); ++it) acc = acc * *it;
    return acc;
  };
  return to_common(b).inverse() * to_common(a);
}

geometry_msgs::msg::TransformStamped TransformBuffer::lookup_msg(const std::string& target, const std::string& source,
                                                                 Time time) const {
  geometry_msgs::msg::TransformStamped m;
  m.header.frame_id = target;
  m.header.stamp = to_stamp(time);
  m.child_frame_id = source;
  m.transform = to_msg(lookup(target, source, time));
  return m;
}

bool TransformBuffer::can_transform(const std::string& target, const std::string& source, Time time) const {
  try {
    lookup(target, source, time);
    return true;
  } catch (const TransformError&) {
    return false;
  }
}

std::vector<std::string> TransformBuffer::frames() const {
  std::lock_guard l(mu_);
  std::set<std::string> s;
  for (const auto& [child, link] : links_) {
    s.insert(child);
    s.insert(link.parent);
  }
  return {s.begin(), s.end()};
}

TransformListener::TransformListener(Node& node, std::shared_ptr<TransformBuffer> buffer) : buffer_(std::move(buffer)) {
  auto feed = [b = buffer_, &node](bool is_static) {
    return [b, is_static, &node](const tf2_msgs::msg::TFMessage& m) {
      for (const auto& t : m.transforms) {
        try {
          b->set_transform(t, is_static);
        } catch (const TransformError& e) {
          CAIRN_WARN(node.logger(), "ignoring transform: " << e.what());
        }
      }
    };
  };
  QoS dyn;
  dyn.keep_last(100);
  tf_sub_ = node.create_subscription<tf2_msgs::msg::TFMessage>("/tf", dyn, feed(false));
  static_sub_ = node.create_subscription<tf2_msgs::msg::TFMessage>("/tf_static", QoS::latched(100), feed(true));
}

}  // namespace cairn
