#include "cairn/people_tracking/segmentation.hpp"

#include <algorithm>
#include <cmath>

namespace cairn::people_tracking {

Eigen::Vector2d Cluster::centroid() const { return centroid(0, points.size()); }

Eigen::Vector2d Cluster::centroid(std::size_t begin, std::size_t end) const {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (std::size_t i = begin; i < end; ++i) c += points[i];
  return end > begin ? Eigen::Vector2d(c / static_cast<double>(end - begin)) : c;
}

std::vector<Cluster> segmentScan(const LaserScan& scan, const SegmentationParams& params) {
  validateScan(scan);
  const std::size_t n = scan.ranges.size();
  const double dtheta = std::abs(scan.angle_increment);

  // Valid returns as (beam, point); clusters are contiguous runs of this list.
  std::vector<std::size_t> beams;
  std::vector<Eigen::Vector2d> pts;
  beams.reserve(n);
  pts.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (scan.valid(i)) {
      beams.push_back(i);
      pts.push_back(scan.point(i));
    }
  }
  std::vector<Cluster> out;
  if (beams.empty()) return out;

  auto flush = [&](std::size_t begin, std::size_t end) {  // [begin, end) into beams/pts
    const std::size_t count = end - begin;
    if (count < params.min_points || count > params.max_points) return;
    Cluster c;
    c.beams.assign(beams.begin() + static_cast<long>(begin), beams.begin() + static_cast<long>(end));
    c.points.assign(pts.begin() + static_cast<long>(begin), pts.begin() + static_cast<long>(end));
    c.jump_prev = begin > 0 ? std::min(params.jump_cap, (pts[begin] - pts[begin - 1]).norm()) : params.jump_cap;
    c.jump_next = end < pts.size() ? std::min(params.jump_cap, (pts[end] - pts[end - 1]).norm()) : params.jump_cap;
    out.push_back(std::move(c));
  };

  std::size_t start = 0;
  for (std::size_t k = 1; k < beams.size(); ++k) {
    const double ra = scan.ranges[beams[k - 1]];
    const double rb = scan.ranges[beams[k]];
    const auto gap = static_cast<long>(beams[k] - beams[k - 1]) - 1;
    // Skipped beams widen the allowed spacing proportionally.
    const double threshold =
        params.jump_base + params.jump_beam_factor * std::min(ra, rb) * dtheta * static_cast<double>(gap + 1);
    const bool same = gap <= params.max_gap_beams && (pts[k] - pts[k - 1]).norm() < threshold;
    if (!same) {
      flush(start, k);
      start = k;
    }
  }
  flush(start, beams.size());
  return out;
}

std::size_t gapSplitIndex(const Cluster& c, double angle_increment, double gap_ratio, double min_gap_beams) {
  const std::size_t n = c.points.size();
  if (n < 3) return 0;
  std::vector<double> gaps(n - 1);
  for (std::size_t i = 1; i < n; ++i) gaps[i - 1] = (c.points[i] - c.points[i - 1]).norm();
  const auto largest = std::max_element(gaps.begin(), gaps.end());
  const double step = *largest;
  const std::size_t index = static_cast<std::size_t>(largest - gaps.begin()) + 1;
  gaps.erase(largest);
  const auto mid = gaps.begin() + static_cast<long>(gaps.size() / 2);
  std::nth_element(gaps.begin(), mid, gaps.end());
  const double spacing = c.centroid().norm() * std::abs(angle_increment);
  return step >= gap_ratio * *mid && step >= min_gap_beams * spacing ? index : 0;
}

}  // namespace cairn::people_tracking
