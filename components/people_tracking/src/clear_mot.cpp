#include "cairn/people_tracking/clear_mot.hpp"

#include "cairn/people_tracking/assignment.hpp"

namespace cairn::people_tracking {

void ClearMot::addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                        const std::vector<Eigen::Vector2d>& dont_care) {
  ++m_.frames;
  m_.gt += gt.size();
  for (const auto& g : gt) seen_gt_[g.id] = true;
  std::vector<int> gt_match(gt.size(), -1);  // index into hyp
  std::vector<int> switched_from(gt.size(), -1);
  std::vector<bool> hyp_used(hyp.size(), false);
  // 1. Keep last frame's correspondences that are still valid.
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const auto it = current_.find(gt[i].id);
    if (it == current_.end()) continue;
    for (std::size_t j = 0; j < hyp.size(); ++j)
      if (!hyp_used[j] && hyp[j].id == it->second && (hyp[j].p - gt[i].p).norm() <= threshold_) {
        gt_match[i] = static_cast<int>(j);
        hyp_used[j] = true;
      }
  }
  // 2. Optimal assignment of the rest.
  std::vector<std::size_t> rows, cols;
  for (std::size_t i = 0; i < gt.size(); ++i)
    if (gt_match[i] < 0) rows.push_back(i);
  for (std::size_t j = 0; j < hyp.size(); ++j)
    if (!hyp_used[j]) cols.push_back(j);
  if (!rows.empty() && !cols.empty()) {
    constexpr double kForbidden = 1e9;
    Eigen::MatrixXd cost(static_cast<long>(rows.size()), static_cast<long>(cols.size()));
    for (std::size_t r = 0; r < rows.size(); ++r)
      for (std::size_t c = 0; c < cols.size(); ++c) {
        const double d = (gt[rows[r]].p - hyp[cols[c]].p).norm();
        cost(static_cast<long>(r), static_cast<long>(c)) = d <= threshold_ ? d : kForbidden;
      }
    const auto match = solveAssignment(cost, kForbidden);
    for (std::size_t r = 0; r < rows.size(); ++r)
      if (match[r] >= 0) {
        const std::size_t j = cols[static_cast<std::size_t>(match[r])];
        gt_match[rows[r]] = static_cast<int>(j);
        hyp_used[j] = true;
        const auto last = last_match_.find(gt[rows[r]].id);
        if (last != last_match_.end() && last->second != hyp[j].id) {
          ++m_.id_switches;
          switched_from[rows[r]] = last->second;
        }
      }
  }
  // 3. Count.
  current_.clear();
  frame_.clear();
  for (std::size_t i = 0; i < gt.size(); ++i) {
    if (gt_match[i] < 0) {
      ++m_.fn;
      continue;
    }
    const MotObject& h = hyp[static_cast<std::size_t>(gt_match[i])];
    ++m_.matches;
    m_.distance_sum += (h.p - gt[i].p).norm();
    current_[gt[i].id] = h.id;
    frame_.push_back({gt[i].id, h.id, switched_from[i]});
    last_match_[gt[i].id] = h.id;
  }
  for (std::size_t j = 0; j < hyp.size(); ++j) {
    if (hyp_used[j]) continue;
    bool ignore = false;
    for (const auto& d : dont_care) ignore |= (hyp[j].p - d).norm() <= threshold_;
    if (ignore) ++m_.ignored;
    else ++m_.fp;
  }
}

MotMetrics ClearMot::metrics() const {
  MotMetrics m = m_;
  m.gt_tracks = seen_gt_.size();
  return m;
}

}  // namespace cairn::people_tracking
