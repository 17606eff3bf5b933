// Occupancy grid conversion and map exports (see occupancy_grid.hpp).
#include "cairn/graph_slam/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cairn/graph_slam/probability_grid.hpp"

namespace cairn::graph_slam {

std::size_t OccupancyGrid::knownCells() const {
  return static_cast<std::size_t>(std::count_if(data.begin(), data.end(), [](std::int8_t v) { return v >= 0; }));
}

namespace {

std::uint8_t pgmValue(std::int8_t v, const MapExportOptions& o) {
  if (v < 0) return 205;
  const double p = v / 100.0;
  if (p >= o.occupied_thresh) return 0;
  if (p <= o.free_thresh) return 254;
  return 205;
}

// Grey image, top row = highest y (image convention).
cv::Mat toImage(const OccupancyGrid& g, const MapExportOptions& o) {
  cv::Mat img(g.height, g.width, CV_8UC1);
  for (int y = 0; y < g.height; ++y) {
    auto* row = img.ptr<std::uint8_t>(g.height - 1 - y);
    for (int x = 0; x < g.width; ++x) row[x] = pgmValue(g.at(x, y), o);
  }
  return img;
}

}  // namespace

OccupancyGrid toOccupancyGrid(const ProbabilityGrid& grid) {
  OccupancyGrid out;
  out.resolution = grid.resolution();
  CellIndex lo, hi;
  if (!grid.knownBounds(lo, hi)) {
    out.origin = grid.origin();
    return out;
  }
  out.width = hi.x - lo.x + 1;
  out.height = hi.y - lo.y + 1;
  out.origin = grid.origin() + grid.resolution() * Eigen::Vector2d(lo.x, lo.y);
  out.data.assign(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height), -1);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      if (grid.known(lo.x + x, lo.y + y))
        out.data[static_cast<std::size_t>(y) * static_cast<std::size_t>(out.width) + static_cast<std::size_t>(x)] =
            static_cast<std::int8_t>(std::lround(100.0 * grid.probability(lo.x + x, lo.y + y)));
  return out;
}

void writeMapServer(const OccupancyGrid& grid, const std::string& stem, const MapExportOptions& options) {
  const std::string pgm = stem + ".pgm";
  const std::string yaml = stem + ".yaml";
  std::FILE* f = std::fopen(pgm.c_str(), "wb");
  if (f == nullptr) throw std::runtime_error(pgm + ": cannot write file");
  const cv::Mat img = toImage(grid, options);
  std::fprintf(f, "P5\n# cairn graph_slam map, %.3f m/pixel\n%d %d\n255\n", grid.resolution, grid.width, grid.height);
  bool ok = true;
  for (int r = 0; r < img.rows && ok; ++r)
    ok = std::fwrite(img.ptr<std::uint8_t>(r), 1, static_cast<std::size_t>(img.cols), f) ==
         static_cast<std::size_t>(img.cols);
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error(pgm + ": error while writing file");
  f = std::fopen(yaml.c_str(), "w");
  if (f == nullptr) throw std::runtime_error(yaml + ": cannot write file");
  std::fprintf(f, "image: %s\nresolution: %.6f\norigin: [%.6f, %.6f, 0.0]\nnegate: 0\noccupied_thresh: %.3f\nfree_thresh: %.3f\n",
               std::filesystem::path(pgm).filename().c_str(), grid.resolution, grid.origin.x(), grid.origin.y(),
               options.occupied_thresh, options.free_thresh);
  if (std::fclose(f) != 0) throw std::runtime_error(yaml + ": error while writing file");
}

void writeMapPng(const OccupancyGrid& grid, const std::vector<Pose2>& trajectory, const std::string& path,
                 const std::vector<Pose2>& highlights) {
  cv::Mat grey = toImage(grid, MapExportOptions{});
  cv::Mat img;
  cv::cvtColor(grey, img, cv::COLOR_GRAY2BGR);
  auto pixel = [&](const Pose2& p) {
    const double cx = (p.t.x() - grid.origin.x()) / grid.resolution;
    const double cy = (p.t.y() - grid.origin.y()) / grid.resolution;
    return cv::Point(static_cast<int>(std::floor(cx)), grid.height - 1 - static_cast<int>(std::floor(cy)));
  };
  for (std::size_t i = 1; i < trajectory.size(); ++i)
    cv::line(img, pixel(trajectory[i - 1]), pixel(trajectory[i]), cv::Scalar(0, 0, 220), 1, cv::LINE_AA);
  for (const auto& h : highlights) cv::circle(img, pixel(h), 2, cv::Scalar(220, 80, 0), cv::FILLED);
  bool ok = false;
  try {
    ok = cv::imwrite(path, img);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  if (!ok) throw std::runtime_error(path + ": cannot write PNG");
}

}  // namespace cairn::graph_slam
