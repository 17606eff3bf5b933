// Laser scan filtering for the SLAM front end: range limits, invalid beams, free-space rays for beams without
// a return, voxel and adaptive voxel downsampling (Cartographer-style, Hess et al. 2016 §IV).
// Stüde Appendix A: r_lim = 30 m maximum range, l_vox = 0.03 m voxel (3D, RTAB-Map); our 2D defaults below
// are documented in components/graph_slam/README.md ("Front end").
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/geometry.hpp"
#include "cairn/sim/types.hpp"

namespace cairn::graph_slam {

struct ScanFilterOptions {
  double min_range = 0.1;     ///< m: beams shorter than this (and shorter than the scan's range_min) are dropped
  double max_range = 30.0;    ///< m: Stüde App. A r_lim; longer returns become misses of length miss_range
  double voxel_size = 0.025;  ///< m: voxel filter of the returns inserted into the submaps
  /// Adaptive voxel filter of the matching points (Cartographer): the largest voxel in [voxel_size,
  /// max_voxel_size] that still keeps at least min_points points (all points if there are fewer).
  int min_points = 150;
  double max_voxel_size = 0.5;
  /// m: beams with no return (+inf, or >= the scan's range_max, or > max_range) become free-space rays of
  /// this length (0 disables).
  double miss_range = 5.0;
};

/// One scan as points in the base frame.
struct RangeData {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< sensor position in the base frame
  std::vector<Eigen::Vector2d> returns;  ///< hit points, base frame, after range filtering (not downsampled)
  std::vector<Eigen::Vector2d> misses;   ///< free-space ray ends, base frame
};

/// Counts of what toRangeData() dropped (for diagnostics).
struct ScanFilterStats {
  int beams = 0;
  int returns = 0;
  int misses = 0;
  int invalid = 0;       ///< NaN, negative, zero, -inf
  int out_of_range = 0;  ///< finite but below min_range
};

/// Converts a scan to range data. Drops NaN / -inf / zero / negative / below-min-range beams; +inf, beams at
/// or above the scan's range_max and beyond o.max_range become misses when o.miss_range > 0. sensor_in_base
/// is the laser mount (pose of the laser frame in the base frame). Never throws; a malformed scan
/// (angle_increment not finite) gives empty range data.
RangeData toRangeData(const sim::LaserScan& scan, const Pose2& sensor_in_base, const ScanFilterOptions& o,
                      ScanFilterStats* stats = nullptr);

/// Keeps the first point of every occupied voxel (square cells of edge `voxel`, aligned at the origin), in
/// input order. voxel <= 0 returns the input.
std::vector<Eigen::Vector2d> voxelFilter(const std::vector<Eigen::Vector2d>& pts, double voxel);

/// Cartographer's adaptive voxel filter: drops points farther than o.max_range from the origin, then
/// returns the voxelFilter() result with the largest edge in [o.voxel_size, o.max_voxel_size] that keeps
/// at least o.min_points points (binary search); all points if there are at most o.min_points.
std::vector<Eigen::Vector2d> adaptiveVoxelFilter(const std::vector<Eigen::Vector2d>& pts,
                                                 const ScanFilterOptions& o);

/// cairn::sim::Pose2 (x, y, theta) as a graph_slam Pose2 (odometry and laser mounts from sim / CARMEN logs).
inline Pose2 toPose2(const sim::Pose2& p) {
  Pose2 q;
  q.t = Eigen::Vector2d(p.x, p.y);
  q.theta = p.theta;
  return q;
}

/// Applies `pose` (base in some frame) to points.
std::vector<Eigen::Vector2d> transformPoints(const Pose2& pose, const std::vector<Eigen::Vector2d>& pts);

}  // namespace cairn::graph_slam
