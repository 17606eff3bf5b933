// Scan filtering: range limits, invalid beams, misses, voxel / adaptive voxel downsampling.
#include "cairn/graph_slam/scan_filter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace cairn::graph_slam {

RangeData toRangeData(const sim::LaserScan& scan, const Pose2& sensor_in_base, const ScanFilterOptions& o,
                      ScanFilterStats* stats) {
  RangeData out;
  out.origin = sensor_in_base.t;
  ScanFilterStats st;
  st.beams = static_cast<int>(scan.ranges.size());
  const double inc = scan.angle_increment;
  const double amin = scan.angle_min;
  if (!std::isfinite(inc) || !std::isfinite(amin)) {
    st.invalid = st.beams;
    if (stats) *stats = st;
    return out;
  }
  const double min_r = std::max(o.min_range, static_cast<double>(scan.range_min));
  // A reading at the scan's range_max is the sensor's "no return" value (SICK: 81.9 m); range_max <= 0 means
  // the scan does not say.
  const double scan_max = scan.range_max > 0.0F ? static_cast<double>(scan.range_max) : std::numeric_limits<double>::infinity();
  const Eigen::Matrix2d R = rotation2(sensor_in_base.theta);
  out.returns.reserve(scan.ranges.size());
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i];
    if (std::isnan(r) || r <= 0.0) {  // NaN, -inf, zero, negative
      ++st.invalid;
      continue;
    }
    const double a = amin + static_cast<double>(i) * inc;
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    if (std::isinf(r) || r >= scan_max || r > o.max_range) {
      if (o.miss_range > 0.0) {
        out.misses.push_back(sensor_in_base.t + R * (o.miss_range * dir));
        ++st.misses;
      } else {
        ++st.out_of_range;
      }
      continue;
    }
    if (r < min_r) {
      ++st.out_of_range;
      continue;
    }
    out.returns.push_back(sensor_in_base.t + R * (r * dir));
  }
  st.returns = static_cast<int>(out.returns.size());
  if (stats) *stats = st;
  return out;
}

std::vector<Eigen::Vector2d> voxelFilter(const std::vector<Eigen::Vector2d>& pts, double voxel) {
  if (!(voxel > 0.0) || pts.size() < 2) return pts;
  const double inv = 1.0 / voxel;
  // (voxel key, input index), sorted by key then index: the first entry of every key is the point kept.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys;
  keys.reserve(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto kx = static_cast<std::int64_t>(std::floor(pts[i].x() * inv));
    const auto ky = static_cast<std::int64_t>(std::floor(pts[i].y() * inv));
    const std::uint64_t key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(kx)) << 32) |
                              static_cast<std::uint32_t>(ky);
    keys.emplace_back(key, static_cast<std::uint32_t>(i));
  }
  std::sort(keys.begin(), keys.end());
  std::vector<char> keep(pts.size(), 0);
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (k == 0 || keys[k].first != keys[k - 1].first) keep[keys[k].second] = 1;
  }
  std::vector<Eigen::Vector2d> out;
  out.reserve(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (keep[i]) out.push_back(pts[i]);
  }
  return out;
}

std::vector<Eigen::Vector2d> adaptiveVoxelFilter(const std::vector<Eigen::Vector2d>& pts,
                                                 const ScanFilterOptions& o) {
  std::vector<Eigen::Vector2d> in;
  in.reserve(pts.size());
  const double max2 = o.max_range * o.max_range;
  for (const auto& p : pts) {
    if (p.squaredNorm() <= max2) in.push_back(p);
  }
  const std::size_t min_points = static_cast<std::size_t>(std::max(0, o.min_points));
  if (in.size() <= min_points) return in;
  const double lo_limit = std::max(o.voxel_size, 1e-4);
  double high = std::max(o.max_voxel_size, lo_limit);
  std::vector<Eigen::Vector2d> result = voxelFilter(in, high);
  if (result.size() >= min_points) return result;
  // Halve until enough points survive, then bisect between the last two edges (ratio 1.1, Cartographer).
  while (high > lo_limit) {
    double low = std::max(high / 2.0, lo_limit);
    result = voxelFilter(in, low);
    if (result.size() >= min_points || low <= lo_limit) {
      if (result.size() < min_points) return result;  // even the smallest voxel keeps too few
      while (high / low > 1.1) {
        const double mid = 0.5 * (low + high);
        auto candidate = voxelFilter(in, mid);
        if (candidate.size() >= min_points) {
          low = mid;
          result = std::move(candidate);
        } else {
          high = mid;
        }
      }
      return result;
    }
    high = low;
  }
  return result;
}

std::vector<Eigen::Vector2d> transformPoints(const Pose2& pose, const std::vector<Eigen::Vector2d>& pts) {
  const Eigen::Matrix2d R = rotation2(pose.theta);
  std::vector<Eigen::Vector2d> out;
  out.reserve(pts.size());
  for (const auto& p : pts) out.push_back(R * p + pose.t);
  return out;
}

}  // namespace cairn::graph_slam
