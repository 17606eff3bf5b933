// Occupancy grid of the SLAM map with nav_msgs/OccupancyGrid semantics, and its exports: map_server PGM + YAML
// and a PNG with the trajectory drawn on it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/geometry.hpp"

namespace cairn::graph_slam {

class ProbabilityGrid;

/// nav_msgs/OccupancyGrid semantics: `data` is row-major starting at the cell whose lower-left corner is
/// `origin` (row 0 = lowest y), values -1 unknown, 0..100 occupancy probability in percent.
struct OccupancyGrid {
  double resolution = 0.05;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< world position of cell (0,0)'s lower-left corner
  int width = 0;
  int height = 0;
  std::vector<std::int8_t> data;

  std::int8_t at(int x, int y) const { return data[static_cast<std::size_t>(y) * width + x]; }
  std::size_t knownCells() const;
};

/// Converts a probability grid (cells never observed → -1, else round(100·p)), cropped to the observed cells.
OccupancyGrid toOccupancyGrid(const ProbabilityGrid& grid);

struct MapExportOptions {
  /// map_server thresholds written into the YAML (and used for the PGM's three grey levels).
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
};

/// Writes `<stem>.pgm` (binary P5; occupied 0, free 254, unknown 205, top row = highest y as map_server
/// expects) and `<stem>.yaml` (image, resolution, origin, negate, thresholds). Throws std::runtime_error
/// "path: what" when a file cannot be written.
void writeMapServer(const OccupancyGrid& grid, const std::string& stem, const MapExportOptions& options = {});

/// Writes a PNG of the map (grey levels as in the PGM) with the trajectory drawn as a red polyline and
/// `highlights` (e.g. loop-closure nodes) as small blue dots.
void writeMapPng(const OccupancyGrid& grid, const std::vector<Pose2>& trajectory, const std::string& path,
                 const std::vector<Pose2>& highlights = {});

}  // namespace cairn::graph_slam
