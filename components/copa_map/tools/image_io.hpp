// PNG/YAML helpers of cairn-copa (OpenCV stays in image_io.cpp).
#pragma once

#include <Eigen/Dense>
#include <string>

#include "cairn/copa_map/gridifier.hpp"

namespace cairn::copa_map::tools {

struct MapImage {
  OccupancyMap map;   // occupancy (map_server thresholds applied)
  std::string image;  // path of the PNG/PGM
};

// map_server YAML (image, resolution, origin, negate, occupied_thresh); throws InputError.
MapImage loadMapYaml(const std::string& yaml_path);

// Writes a heat map of `values` (rows = x2 cells from bottom, cols = x1 cells) over the map region
// [x0, x0 + cols*cell] x [y0, y0 + rows*cell]; NaN cells are transparent. Colour scale 0..vmax.
void writeHeatmapPng(const std::string& path, const MapImage& map, const Eigen::MatrixXd& values, double x0,
                     double y0, double cell, double vmax);

}  // namespace cairn::copa_map::tools
