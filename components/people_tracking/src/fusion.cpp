#include "cairn/people_tracking/fusion.hpp"

#include <Eigen/Cholesky>
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

std::vector<std::pair<std::size_t, std::size_t>> nearestPairs(const std::vector<PersonDetection>& a,
                                                              const std::vector<PersonDetection>& b,
                                                              const FusionParams& params) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const Eigen::Vector2d nu = a[i].position - b[j].position;
      if (nu.norm() > params.max_pair_distance) continue;
      if (params.gate_chi2 <= 0.0) {
        candidates.emplace_back(nu.norm(), i, j);
        continue;
      }
      const double d2 = nu.dot((a[i].covariance + b[j].covariance).ldlt().solve(nu));
      if (d2 <= params.gate_chi2) candidates.emplace_back(d2, i, j);
    }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> ua(a.size(), false), ub(b.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const auto& [d, i, j] : candidates) {
    if (ua[i] || ub[j]) continue;
    ua[i] = ub[j] = true;
    out.emplace_back(i, j);
  }
  return out;
}

namespace {
std::vector<PersonDetection> fuseTwo(const std::vector<PersonDetection>& a, const std::vector<PersonDetection>& b,
                                     const FusionParams& params) {
  std::vector<bool> ua(a.size(), false), ub(b.size(), false);
  std::vector<PersonDetection> out;
  for (const auto& [i, j] : nearestPairs(a, b, params)) {
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
