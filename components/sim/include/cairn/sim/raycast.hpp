// 2D ray casting against line segments and circles.
//
// SegmentGrid buckets the static segments into a uniform grid (each cell lists the segments that
// cross it) and walks a ray through the cells with a 3D-DDA-style traversal (Amanatides & Woo 1987,
// "A Fast Voxel Traversal Algorithm for Ray Tracing"), testing only the segments of the visited cells
// and stopping at the first cell whose exit lies beyond the closest hit. castNaive() is the baseline
// that tests every segment for every ray.
#pragma once

#include <cstdint>
#include <vector>

#include "cairn/sim/types.hpp"

namespace cairn::sim {

struct RayHit {
  double range = 0.0;        ///< distance along the ray (valid if hit)
  float reflectivity = 0.0F;
  bool hit = false;
};

/// Intersection of the ray o + t d (|d| = 1, t >= 0) with a segment; returns t or a negative value.
double raySegment(Vec2 o, Vec2 d, Vec2 a, Vec2 b);
/// Intersection of the ray o + t d with a circle (first crossing from outside); negative if none
/// (also if o lies inside the circle).
double rayCircle(Vec2 o, Vec2 d, Vec2 c, double r);

class SegmentGrid {
 public:
  /// cell_size <= 0 picks one from the mean segment length and the bounds.
  explicit SegmentGrid(std::vector<Segment> segments, double cell_size = 0.0);

  /// Closest hit along the ray from o in unit direction d up to max_range.
  RayHit cast(Vec2 o, Vec2 d, double max_range) const;
  /// True if any segment comes closer than r to c (robot footprint collision).
  bool intersectsDisc(Vec2 c, double r) const;
  /// Distance from p to the closest segment (up to max_dist; returns max_dist if none is closer).
  double distanceToNearest(Vec2 p, double max_dist) const;

  const std::vector<Segment>& segments() const { return segments_; }
  double cellSize() const { return cell_; }
  int cellsX() const { return nx_; }
  int cellsY() const { return ny_; }

 private:
  struct Packed {  // a and e = b - a, laid out for the inner loop
    double ax, ay, ex, ey;
    float reflectivity;
  };
  std::vector<Segment> segments_;
  std::vector<Packed> packed_;
  double cell_ = 1.0;
  double inv_cell_ = 1.0;
  Vec2 min_;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> cell_start_;  ///< CSR offsets, size nx*ny+1
  std::vector<std::uint32_t> cell_items_;
};

/// Baseline: tests the ray against every segment.
RayHit castNaive(const std::vector<Segment>& segments, Vec2 o, Vec2 d, double max_range);

}  // namespace cairn::sim
