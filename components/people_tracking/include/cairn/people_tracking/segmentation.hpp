// Jump-distance segmentation of a scan into clusters with a range-adaptive threshold.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "cairn/people_tracking/scan.hpp"

namespace cairn::people_tracking {

struct SegmentationParams {
  // Two consecutive valid returns belong to one cluster when their distance is below
  //   jump_base + jump_beam_factor * min(r_i, r_j) * |angle_increment|
  // i.e. a fixed part plus a multiple of the lateral beam spacing at that range (range-adaptive, as in
  // Arras et al. 2007 / Dietmayer et al. 2001).
  // Not given by the seeds. 0.05 m + 1 spacing (0.09 m at 7 m instead of 0.22 m) with retrained models gave 12 %
  // fewer misses on the open people bench but more false positives among the simulator office's walls and
  // furniture (up to 10x with the sim-trained model): not adopted (docs/benchmarks.md "Segmentation thresholds").
  double jump_base = 0.10;        // m
  double jump_beam_factor = 3.0;  // multiples of the beam spacing r * dtheta
  int max_gap_beams = 1;          // invalid beams tolerated inside a cluster (dropouts)
  std::size_t min_points = 3;     // smaller clusters are dropped
  std::size_t max_points = 400;   // larger clusters are dropped (long walls)
  double jump_cap = 5.0;          // m, neighbour jump distance when there is no neighbour
};

struct Cluster {
  std::vector<std::size_t> beams;      // beam indices (scan order)
  std::vector<Eigen::Vector2d> points;  // sensor frame
  double jump_prev = 0.0;              // distance from first point to the preceding valid return (capped)
  double jump_next = 0.0;              // distance from last point to the following valid return (capped)
  [[nodiscard]] Eigen::Vector2d centroid() const;
  // Mean of points [begin, end) (a part of the cluster, e.g. one of two legs: gapSplitIndex).
  [[nodiscard]] Eigen::Vector2d centroid(std::size_t begin, std::size_t end) const;
};

// Throws InputError on malformed scan metadata (validateScan). NaN/inf beams split clusters.
std::vector<Cluster> segmentScan(const LaserScan& scan, const SegmentationParams& params = {});

// Two objects in one cluster. Where one leg stands partly behind the other, closer in depth than the jump threshold
// (0.22 m at 7 m), both legs form one cluster; inside each leg consecutive returns are about a beam spacing apart,
// the step between the legs is several spacings. Returns the index i (0 < i < n) such that points [0, i) and
// [i, n) are the two objects, or 0 for none: the largest distance between consecutive returns, when it is at least
// gap_ratio times the median of the other distances and min_gap_beams beam spacings at the cluster's range (one
// missing return inside an object makes two spacings). Clusters of fewer than 3 points are never split.
std::size_t gapSplitIndex(const Cluster& c, double angle_increment, double gap_ratio, double min_gap_beams);

}  // namespace cairn::people_tracking
