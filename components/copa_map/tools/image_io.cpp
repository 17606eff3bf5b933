#include "image_io.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cairn/copa_map/io.hpp"
#include "cairn/strict_number.hpp"

namespace cairn::copa_map::tools {
namespace {
long lineOf(const YAML::Node& n) { return std::max(0, n.Mark().line + 1); }

// A finite number, or InputError naming the file, line and key.
double yamlNumber(const std::string& path, const YAML::Node& n, const std::string& key) {
  const std::string text = n.IsScalar() ? n.Scalar() : std::string();
  const auto x = cairn::strict_number::parse_finite(text);
  if (!x) throw InputError(path, lineOf(n), "'" + key + "' expects a number, got '" + text + "'");
  return *x;
}
}  // namespace

MapImage loadMapYaml(const std::string& yaml_path) {
  std::ifstream in = openInputFile(yaml_path, "map YAML");
  YAML::Node root;
  try {
    root = YAML::Load(in);
  } catch (const YAML::Exception& e) {
    throw InputError(yaml_path, e.mark.line + 1, "YAML syntax: " + e.msg);
  }
  if (!root.IsMap())
    throw InputError(yaml_path, lineOf(root), "map YAML needs image, resolution > 0 and origin");
  std::string image;
  double res = 0, occ_th = 0.65;
  int negate = 0;
  std::vector<double> origin;
  std::set<std::string> seen;
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    const YAML::Node& v = kv.second;
    const long ln = lineOf(kv.first);
    if (!seen.insert(key).second) throw InputError(yaml_path, ln, "duplicate key '" + key + "'");
    if (key == "image") {
      if (!v.IsScalar() || v.Scalar().empty()) throw InputError(yaml_path, ln, "'image' expects a file name");
      image = v.Scalar();
    } else if (key == "resolution") {
      res = yamlNumber(yaml_path, v, key);
    } else if (key == "negate") {
      if (!v.IsScalar() || (v.Scalar() != "0" && v.Scalar() != "1"))
        throw InputError(yaml_path, ln,
                         "'negate' expects 0 or 1, got '" + (v.IsScalar() ? v.Scalar() : "") + "'");
      negate = v.Scalar() == "1";
    } else if (key == "occupied_thresh") {
      occ_th = yamlNumber(yaml_path, v, key);
      if (occ_th < 0.0 || occ_th > 1.0) throw InputError(yaml_path, ln, "'occupied_thresh' must be in [0, 1]");
    } else if (key == "free_thresh") {
      yamlNumber(yaml_path, v, key);  // map_server key, not used here
    } else if (key == "mode") {
      if (!v.IsScalar()) throw InputError(yaml_path, ln, "'mode' expects trinary, scale or raw");
    } else if (key == "origin") {
      if (!v.IsSequence() || v.size() < 2 || v.size() > 3)
        throw InputError(yaml_path, ln, "'origin' expects [x, y] or [x, y, yaw]");
      for (const auto& item : v) origin.push_back(yamlNumber(yaml_path, item, key));
    } else {
      throw InputError(yaml_path, ln,
                       "unknown key '" + key +
                           "' (map_server keys: image, resolution, origin, negate, "
                           "occupied_thresh, free_thresh, mode)");
    }
  }
  if (image.empty() || !(res > 0) || origin.size() < 2)
    throw InputError(yaml_path, lineOf(root), "map YAML needs image, resolution > 0 and origin");
  MapImage m;
  m.image = std::filesystem::path(image).is_absolute()
                ? image
                : (std::filesystem::path(yaml_path).parent_path() / image).string();
  const cv::Mat img = cv::imread(m.image, cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw InputError(m.image, 0, "cannot read map image");
  m.map.width = img.cols;
  m.map.height = img.rows;
  m.map.resolution = res;
  m.map.origin_x = origin[0];
  m.map.origin_y = origin[1];
  m.map.occupied.assign(static_cast<std::size_t>(img.cols) * img.rows, 0);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const double v = img.at<unsigned char>(r, c) / 255.0;
      const double p = negate ? v : 1.0 - v;  // map_server: occupancy probability
      // Image row 0 is the top (largest x2).
      m.map.occupied[static_cast<std::size_t>(img.rows - 1 - r) * img.cols + c] = p > occ_th ? 1 : 0;
    }
  return m;
}

void writeHeatmapPng(const std::string& path, const MapImage& map, const Eigen::MatrixXd& values, double x0,
                     double y0, double cell, double vmax) {
  const OccupancyMap& om = map.map;
  const int px = std::max(1, static_cast<int>(std::lround(cell / om.resolution)));
  const int W = static_cast<int>(values.cols()) * px, H = static_cast<int>(values.rows()) * px;
  cv::Mat out(H, W, CV_8UC3);
  cv::Mat grey(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) grey.at<unsigned char>(0, i) = static_cast<unsigned char>(i);
  cv::Mat lut;
  cv::applyColorMap(grey, lut, cv::COLORMAP_INFERNO);
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) {
      const double x = x0 + (c + 0.5) * om.resolution, y = y0 + (H - r - 0.5) * om.resolution;
      const bool occ = om.occupiedAt(x, y);
      const double v = values(static_cast<Eigen::Index>((H - 1 - r) / px), c / px);
      cv::Vec3b colour(235, 235, 235);
      if (std::isfinite(v)) {
        const int idx = std::clamp(static_cast<int>(std::lround(255.0 * v / std::max(vmax, 1e-12))), 0, 255);
        colour = lut.at<cv::Vec3b>(0, idx);
      }
      if (occ) colour = cv::Vec3b(0, 0, 0);
      out.at<cv::Vec3b>(r, c) = colour;
    }
  if (!cv::imwrite(path, out)) throw InputError(path, 0, "cannot write PNG");
}

}  // namespace cairn::copa_map::tools
