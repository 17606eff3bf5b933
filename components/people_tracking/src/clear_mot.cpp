#include "cairn/people_tracking/clear_mot.hpp"

#include "cairn/people_tracking/assignment.hpp"

namespace cairn::people_tracking {

std::vector<MotObject> dropDontCareHypotheses(const std::vector<MotObject>& gt, const std::vector<MotObject>& all_hyp,
                                              const std::vector<Eigen::Vector2d>& dont_care, double threshold,
                                              std::size_t* ignored) {
  if (dont_care.empty() || all_hyp.empty()) return all_hyp;
  constexpr double kForbidden = 1e9;
  const std::size_t rows = gt.size() + dont_care.size();
  Eigen::MatrixXd cost(static_cast<long>(rows), static_cast<long>(all_hyp.size()));
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < all_hyp.size(); ++c) {
      const Eigen::Vector2d& o = r < gt.size() ? gt[r].p : dont_care[r - gt.size()];
      const double d = (o - all_hyp[c].p).norm();
      cost(static_cast<long>(r), static_cast<long>(c)) = d <= threshold ? d : kForbidden;
    }
  const std::vector<int> match = solveAssignment(cost, kForbidden);
  std::vector<bool> drop(all_hyp.size(), false);
  for (std::size_t r = gt.size(); r < rows; ++r)
    if (match[r] >= 0) drop[static_cast<std::size_t>(match[r])] = true;
  std::vector<MotObject> hyp;
  for (std::size_t c = 0; c < all_hyp.size(); ++c) {
    if (!drop[c]) hyp.push_back(all_hyp[c]);
    else if (ignored) ++*ignored;
  }
  return hyp;
}

void ClearMot::addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& all_hyp,
                        const std::vector<Eigen::Vector2d>& dont_care) {
  constexpr double kForbidden = 1e9;
  // 0. Don't-care objects: a track on a person who does not count can then not be matched to a counted neighbour.
  kept_ = dropDontCareHypotheses(gt, all_hyp, dont_care, threshold_, &m_.ignored);
  const std::vector<MotObject>& hyp = kept_;
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
    const auto [it, first] = hyp_last_.emplace(h.id, gt[i].id);
    if (!first && it->second != gt[i].id) {
      ++m_.id_transfers;
      it->second = gt[i].id;
    }
  }
  for (std::size_t j = 0; j < hyp.size(); ++j)
    if (!hyp_used[j]) ++m_.fp;
}

MotMetrics ClearMot::metrics() const {
  MotMetrics m = m_;
  m.gt_tracks = seen_gt_.size();
  return m;
}

}  // namespace cairn::people_tracking
