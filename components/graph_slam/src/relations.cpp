// Kümmerle et al. 2009 relative-pose metric (see relations.hpp).
#include "cairn/graph_slam/relations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "cairn/sim/carmen.hpp"
#include "cairn/sim/world.hpp"  // InputError
#include "cairn/strict_number.hpp"

namespace cairn::graph_slam {
namespace {

using sim::InputError;

// Splits a line into numbers; returns false if any token is not a finite number.
bool parseNumbers(const std::string& line, std::vector<double>& out) {
  out.clear();
  std::istringstream in(line);
  std::string tok;
  while (in >> tok) {
    const auto v = strict_number::parse_finite(tok);
    if (!v) return false;
    out.push_back(*v);
  }
  return true;
}

bool skippable(const std::string& line) {
  const auto p = line.find_first_not_of(" \t\r");
  return p == std::string::npos || line[p] == '#';
}

template <typename Fn>
void forEachLine(const std::string& path, Fn&& fn) {
  std::error_code ec;  // an ifstream opens a directory and reads nothing from it: not an empty file
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, 0, "cannot open file: is a directory");
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open file");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (skippable(line)) continue;
    fn(line, n);
  }
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double stddev(const std::vector<double>& v, double m) {
  if (v.size() < 2) return 0.0;
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

}  // namespace

std::vector<Relation> readRelations(const std::string& path) {
  std::vector<Relation> out;
  std::vector<double> v;
  forEachLine(path, [&](const std::string& line, int n) {
    if (!parseNumbers(line, v) || v.size() != 8)
      throw InputError(path, n, "expected 8 numbers `t1 t2 x y z roll pitch yaw`");
    Relation r;
    r.t1 = v[0];
    r.t2 = v[1];
    r.delta.t = {v[2], v[3]};
    r.delta.theta = normalizeAngle(v[7]);
    r.line = n;
    out.push_back(r);
  });
  return out;
}

std::vector<StampedPose> readPoses(const std::string& path) {
  std::vector<StampedPose> out;
  std::vector<double> v;
  forEachLine(path, [&](const std::string& line, int n) {
    if (!parseNumbers(line, v) || v.size() != 4) throw InputError(path, n, "expected 4 numbers `timestamp x y theta`");
    out.push_back({v[0], {{v[1], v[2]}, normalizeAngle(v[3])}});
  });
  return out;
}

void writePoses(const std::string& path, const std::vector<StampedPose>& poses) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw InputError(path, 0, "cannot write file");
  for (const auto& p : poses)
    std::fprintf(f, "%.6f %.9g %.9g %.9g\n", p.stamp, p.pose.t.x(), p.pose.t.y(), p.pose.theta);
  if (std::fclose(f) != 0) throw InputError(path, 0, "error while writing file");
}

RelationsResult evaluateRelations(const std::vector<Relation>& relations, std::vector<StampedPose> poses,
                                  const RelationsOptions& options) {
  std::sort(poses.begin(), poses.end(), [](const auto& a, const auto& b) { return a.stamp < b.stamp; });
  auto find = [&](double t) -> const StampedPose* {
    auto it = std::lower_bound(poses.begin(), poses.end(), t - options.stamp_tolerance,
                               [](const StampedPose& p, double s) { return p.stamp < s; });
    if (it == poses.end() || it->stamp > t + options.stamp_tolerance) return nullptr;
    return &*it;
  };
  RelationsResult r;
  r.relations = relations.size();
  std::vector<double> te, re;
  for (const auto& rel : relations) {
    const StampedPose* a = find(rel.t1);
    const StampedPose* b = find(rel.t2);
    if (a == nullptr || b == nullptr) {
      if (r.missing++ == 0) r.first_missing_line = rel.line;
      continue;
    }
    const Pose2 est = compose(inverse(a->pose), b->pose);
    const Pose2 err = compose(inverse(rel.delta), est);
    te.push_back(err.t.norm());
    re.push_back(std::abs(normalizeAngle(err.theta)));
  }
  r.used = te.size();
  r.trans_mean = mean(te);
  r.trans_std = stddev(te, r.trans_mean);
  r.rot_mean = mean(re);
  r.rot_std = stddev(re, r.rot_mean);
  if (!te.empty()) {
    r.trans_max = *std::max_element(te.begin(), te.end());
    r.rot_max = *std::max_element(re.begin(), re.end());
  }
  return r;
}

namespace {

// Key of a scan's readings (exact: corrected logs copy the raw readings verbatim).
std::string rangesKey(const std::vector<float>& r) {
  return std::string(reinterpret_cast<const char*>(r.data()), r.size() * sizeof(float));
}

Pose2 toPose(const sim::Pose2& p) { return Pose2{{p.x, p.y}, p.theta}; }

}  // namespace

std::vector<StampedPose> odometryTrajectory(const std::string& carmen_log) {
  sim::CarmenReader reader(carmen_log);
  sim::CarmenRecord rec;
  std::vector<StampedPose> out;
  while (reader.next(rec))
    if (const auto* l = std::get_if<sim::CarmenLaser>(&rec); l != nullptr && l->has_pose)
      out.push_back({l->scan.stamp, toPose(l->robot_pose)});
  return out;
}

TrajectoryAgreement compareWithCorrectedLog(const std::string& corrected_log, const std::string& raw_log,
                                            const std::vector<StampedPose>& poses, double stamp_tolerance) {
  std::unordered_map<std::string, double> raw_stamp;
  Pose2 mount;
  {
    sim::CarmenReader reader(raw_log);
    sim::CarmenRecord rec;
    bool first = true;
    while (reader.next(rec)) {
      const auto* l = std::get_if<sim::CarmenLaser>(&rec);
      if (l == nullptr) continue;
      raw_stamp.emplace(rangesKey(l->scan.ranges), l->scan.stamp);
      if (first && l->has_pose) mount = compose(inverse(toPose(l->robot_pose)), toPose(l->laser_pose));
      first = false;
    }
  }
  std::vector<StampedPose> sorted = poses;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.stamp < b.stamp; });
  std::vector<std::pair<Pose2, Pose2>> pairs;  // (estimate as laser pose, corrected laser pose)
  TrajectoryAgreement r;
  sim::CarmenReader reader(corrected_log);
  sim::CarmenRecord rec;
  while (reader.next(rec)) {
    const auto* l = std::get_if<sim::CarmenLaser>(&rec);
    if (l == nullptr || !l->has_pose) continue;
    ++r.corrected_scans;
    const auto it = raw_stamp.find(rangesKey(l->scan.ranges));
    if (it == raw_stamp.end()) continue;
    const double t = it->second;
    auto p = std::lower_bound(sorted.begin(), sorted.end(), t - stamp_tolerance,
                              [](const StampedPose& a, double s) { return a.stamp < s; });
    if (p == sorted.end() || p->stamp > t + stamp_tolerance) continue;
    pairs.emplace_back(compose(p->pose, mount), toPose(l->laser_pose));
  }
  r.matched = pairs.size();
  if (pairs.size() < 2) return r;
  // Least-squares rigid alignment of the estimate onto the corrected positions (2D Horn/Umeyama).
  Eigen::Vector2d ca = Eigen::Vector2d::Zero(), cb = Eigen::Vector2d::Zero();
  for (const auto& [a, b] : pairs) {
    ca += a.t;
    cb += b.t;
  }
  ca /= static_cast<double>(pairs.size());
  cb /= static_cast<double>(pairs.size());
  double sxx = 0.0, sxy = 0.0;
  for (const auto& [a, b] : pairs) {
    const Eigen::Vector2d u = a.t - ca, v = b.t - cb;
    sxx += u.dot(v);
    sxy += u.x() * v.y() - u.y() * v.x();
  }
  const double rot = std::atan2(sxy, sxx);
  const Eigen::Matrix2d R = rotation2(rot);
  double se = 0.0, sh = 0.0;
  for (const auto& [a, b] : pairs) {
    const double e = (R * (a.t - ca) + cb - b.t).norm();
    se += e * e;
    r.ate_max = std::max(r.ate_max, e);
    const double h = normalizeAngle(a.theta + rot - b.theta);
    sh += h * h;
  }
  r.ate_rmse = std::sqrt(se / static_cast<double>(pairs.size()));
  r.heading_rmse = std::sqrt(sh / static_cast<double>(pairs.size()));
  return r;
}

}  // namespace cairn::graph_slam
