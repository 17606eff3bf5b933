// Static occupancy for the tracker: legs on or next to occupied cells of a static map (the SLAM map in the
// component, the world's geometry in the bench) are dropped. Wall ends and furniture seen edge-on from far away
// give short clusters the leg classifier accepts, and tracks on them never go away (they do not move, and the
// beams keep hitting them); a track that followed a person past a wall end also stays there once the person is
// gone, so such legs neither start nor update tracks (SPENCER filters detections with the static map the same
// way; leg_tracker only starts tracks in free space). Cost: a person whose leg is within the margin of a mapped
// wall (leaning on it) is not seen there.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "cairn/people_tracking/scan.hpp"
#include "cairn/people_tracking/scene.hpp"

namespace cairn::people_tracking {

struct StaticMap {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // map-frame corner of cell (0, 0)
  double resolution = 0.05;                          // m per cell
  int width = 0, height = 0;
  std::vector<std::uint8_t> occupied;  // width * height, row-major from the origin (ROS OccupancyGrid order)
  Pose2 map_from_tracking;             // tracking-frame point -> map frame (identity when they coincide)

  // Whether an occupied cell's centre lies within `radius` of p (tracking frame). Outside the grid: free.
  [[nodiscard]] bool occupiedWithin(const Eigen::Vector2d& p_tracking, double radius) const;
  // The cell (column, row) containing a map-frame point; may lie outside the grid.
  [[nodiscard]] Eigen::Vector2i cellOf(const Eigen::Vector2d& p_map) const;
  // Index into `occupied` of a cell inside the grid.
  [[nodiscard]] std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
  }
};

// The scene's static geometry (segments and circles that are not people) rasterised at `resolution`; the grid
// covers the geometry plus one cell. Cells a segment or circle outline passes through are occupied.
StaticMap rasterize(const Scene& scene, double resolution = 0.05);

}  // namespace cairn::people_tracking
