#include "image_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "cairn/copa_map/io.hpp"

namespace cairn::copa_map::tools {
namespace {
std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

// A finite number, or InputError naming the file, line and key.
double yamlNumber(const std::string& path, long line, const std::string& key, const std::string& text) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(x))
    throw InputError(path, line, "'" + key + "' expects a number, got '" + text + "'");
  return x;
}
}  // namespace

MapImage loadMapYaml(const std::string& yaml_path) {
  std::ifstream in(yaml_path);
  if (!in) throw InputError(yaml_path, 0, "cannot open map YAML");
  std::string line, image, list_key;
  double res = 0, occ_th = 0.65;
  int negate = 0;
  std::vector<double> origin;
  long ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (t[0] == '-' && list_key == "origin") {
      origin.push_back(yamlNumber(yaml_path, ln, "origin", trim(t.substr(1))));
      continue;
    }
    const auto c = t.find(':');
    if (c == std::string::npos) throw InputError(yaml_path, ln, "expected 'key: value'");
    const std::string key = trim(t.substr(0, c)), val = trim(t.substr(c + 1));
    list_key = val.empty() ? key : "";
    if (key == "image") image = val;
    else if (key == "resolution") res = yamlNumber(yaml_path, ln, key, val);
    else if (key == "negate") {
      if (val != "0" && val != "1") throw InputError(yaml_path, ln, "'negate' expects 0 or 1, got '" + val + "'");
      negate = val == "1";
    } else if (key == "occupied_thresh") {
      occ_th = yamlNumber(yaml_path, ln, key, val);
      if (occ_th < 0.0 || occ_th > 1.0) throw InputError(yaml_path, ln, "'occupied_thresh' must be in [0, 1]");
    } else if (key == "origin" && !val.empty()) {
      std::string v = val;
      std::replace(v.begin(), v.end(), '[', ' ');
      std::replace(v.begin(), v.end(), ']', ' ');
      std::replace(v.begin(), v.end(), ',', ' ');
      std::stringstream ss(v);
      std::string item;
      while (ss >> item) origin.push_back(yamlNumber(yaml_path, ln, key, item));
    }
  }
  if (image.empty() || !(res > 0) || origin.size() < 2)
    throw InputError(yaml_path, ln, "map YAML needs image, resolution > 0 and origin");
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
