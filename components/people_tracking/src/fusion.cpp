#include "cairn/people_tracking/fusion.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <tuple>

namespace cairn::people_tracking {

PersonDetection fusePair(const PersonDetection& a, const PersonDetection& b) {
  const Eigen::Matrix2d ia = a.covariance.inverse();
  const Eigen::Matrix2d ib = b.covariance.inverse();
  PersonDetection f = a;
  f.covariance = (ia + ib).inverse();
  f.position = f.covariance * (ia * a.position + ib * b.position);
  f.confidence = 1.0 - (1.0 - a.confidence) * (1.0 - b.confidence);
  f.leg_separation = std::max(a.leg_separation, b.leg_separation);
  f.legs = std::max(a.legs, b.legs);
  return f;
}

namespace {
std::vector<PersonDetection> fuseTwo(const std::vector<PersonDetection>& a, const std::vector<PersonDetection>& b,
                                     const FusionParams& params) {
  // Nearest pairs first: repeatedly take the globally closest unused pair within the gate.
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const double d = (a[i].position - b[j].position).norm();
      if (d <= params.max_pair_distance) pairs.emplace_back(d, i, j);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> ua(a.size(), false), ub(b.size(), false);
  std::vector<PersonDetection> out;
  for (const auto& [d, i, j] : pairs) {
    if (ua[i] || ub[j]) continue;
    ua[i] = ub[j] = true;
    out.push_back(fusePair(a[i], b[j]));
  }
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!ua[i]) out.push_back(a[i]);
  for (std::size_t j = 0; j < b.size(); ++j)
    if (!ub[j]) out.push_back(b[j]);
  return out;
}
}  // namespace

std::vector<PersonDetection> fuseDetections(const std::vector<std::vector<PersonDetection>>& sources,
                                            const FusionParams& params) {
  std::vector<PersonDetection> fused;
  for (const auto& s : sources) fused = fuseTwo(fused, s, params);
  return fused;
}

}  // namespace cairn::people_tracking
