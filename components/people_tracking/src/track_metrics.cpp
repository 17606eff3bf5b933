#include "cairn/people_tracking/track_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/people_tracking/assignment.hpp"

namespace cairn::people_tracking {

namespace {
constexpr double kForbidden = 1e9;
// S >= alpha, with a tolerance so that S = 1 - 0.5/1.0 counts at alpha = 0.5.
bool reaches(double s, int k) { return s >= HotaMetrics::alpha(k) - 1e-9; }

// A (ground truth, hypothesis) pair of dense indices as one map key, and back.
std::uint64_t pairKey(int g, int h) { return (std::uint64_t(std::uint32_t(g)) << 32) | std::uint32_t(h); }
int keyGt(std::uint64_t k) { return static_cast<int>(k >> 32); }
int keyHyp(std::uint64_t k) { return static_cast<int>(k & 0xffffffffu); }

// Dense index of `id` (the next free one the first time it is seen).
int denseIndex(std::unordered_map<int, int>& index, int id) {
  return index.emplace(id, static_cast<int>(index.size())).first->second;
}
}  // namespace

Hota::Hota(double zero_distance, double dont_care_threshold)
    : zero_distance_(zero_distance), dont_care_threshold_(dont_care_threshold) {}

void Hota::addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& all_hyp,
                    const std::vector<Eigen::Vector2d>& dont_care) {
  const std::vector<MotObject> hyp = dropDontCareHypotheses(gt, all_hyp, dont_care, dont_care_threshold_);
  // Dense indices of this frame's objects, counting the frames each is present in.
  auto present = [](std::unordered_map<int, int>& index, std::vector<std::size_t>& frames, const std::vector<MotObject>& objects) {
    std::vector<int> out;
    for (const MotObject& o : objects) {
      const int i = denseIndex(index, o.id);
      if (static_cast<std::size_t>(i) == frames.size()) frames.push_back(0);
      ++frames[static_cast<std::size_t>(i)];
      out.push_back(i);
    }
    return out;
  };
  const std::vector<int> gi = present(gt_index_, gt_frames_, gt), hi = present(hyp_index_, hyp_frames_, hyp);
  gt_total_ += gt.size();
  hyp_total_ += hyp.size();
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < gt.size(); ++i)
    for (std::size_t j = 0; j < hyp.size(); ++j) {
      const double s = 1.0 - (gt[i].p - hyp[j].p).norm() / zero_distance_;
      if (s <= 0.0) continue;
      pairs.push_back({gi[i], hi[j], s});
      for (int k = 0; k < HotaMetrics::kAlphas; ++k)
        if (reaches(s, k)) ++potential_[static_cast<std::size_t>(k)][pairKey(gi[i], hi[j])];
    }
  frames_.push_back(std::move(pairs));
}

HotaMetrics Hota::metrics() const {
  HotaMetrics m;
  // Ass-IoU of a pair matched in `both` frames: TPA / (TPA + FNA + FPA).
  auto assIou = [&](int g, int h, double both) {
    return both / (double(gt_frames_[static_cast<std::size_t>(g)]) + double(hyp_frames_[static_cast<std::size_t>(h)]) - both);
  };
  double loca_sum = 0.0;
  int loca_n = 0;  // LocA: over the thresholds at which anything was matched
  for (int k = 0; k < HotaMetrics::kAlphas; ++k) {
    const auto& potential = potential_[static_cast<std::size_t>(k)];
    std::unordered_map<std::uint64_t, std::size_t> matched;
    std::size_t tp = 0;
    double loc = 0.0;
    for (const std::vector<Pair>& pairs : frames_) {
      std::vector<const Pair*> cand;
      for (const Pair& p : pairs)
        if (reaches(p.s, k)) cand.push_back(&p);
      if (cand.empty()) continue;
      std::vector<int> rows, cols;  // dense ids in this frame's candidate pairs
      for (const Pair* p : cand) {
        if (std::find(rows.begin(), rows.end(), p->g) == rows.end()) rows.push_back(p->g);
        if (std::find(cols.begin(), cols.end(), p->h) == cols.end()) cols.push_back(p->h);
      }
      // solveAssignment first maximises the number of non-forbidden matches, then minimises the cost: the paper's
      // 1/eps + A_max + eps*S.
      Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(static_cast<long>(rows.size()), static_cast<long>(cols.size()), kForbidden);
      Eigen::MatrixXd sim = Eigen::MatrixXd::Zero(cost.rows(), cost.cols());
      for (const Pair* p : cand) {
        const long r = std::find(rows.begin(), rows.end(), p->g) - rows.begin();
        const long c = std::find(cols.begin(), cols.end(), p->h) - cols.begin();
        const double a_max = assIou(p->g, p->h, double(potential.at(pairKey(p->g, p->h))));
        cost(r, c) = -(a_max + 1e-3 * p->s);
        sim(r, c) = p->s;
      }
      const std::vector<int> match = solveAssignment(cost, kForbidden);
      for (std::size_t r = 0; r < rows.size(); ++r) {
        if (match[r] < 0) continue;
        ++tp;
        ++matched[pairKey(rows[r], cols[static_cast<std::size_t>(match[r])])];
        loc += sim(static_cast<long>(r), match[r]);
      }
    }
    double ass = 0.0;
    for (const auto& [kk, n] : matched)
      ass += double(n) * assIou(keyGt(kk), keyHyp(kk), double(n));
    const double det_denominator = double(gt_total_ + hyp_total_ - tp);
    const auto i = static_cast<std::size_t>(k);
    m.assa_alpha[i] = tp ? ass / double(tp) : 0.0;
    m.deta_alpha[i] = det_denominator > 0 ? double(tp) / det_denominator : 0.0;
    m.loca_alpha[i] = tp ? loc / double(tp) : 0.0;
    m.hota_alpha[i] = std::sqrt(m.deta_alpha[i] * m.assa_alpha[i]);
    m.hota += m.hota_alpha[i] / HotaMetrics::kAlphas;
    m.deta += m.deta_alpha[i] / HotaMetrics::kAlphas;
    m.assa += m.assa_alpha[i] / HotaMetrics::kAlphas;
    if (tp) {
      loca_sum += m.loca_alpha[i];
      ++loca_n;
    }
  }
  m.loca = loca_n ? loca_sum / loca_n : 0.0;
  return m;
}

void IdF1::addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& all_hyp,
                    const std::vector<Eigen::Vector2d>& dont_care) {
  const std::vector<MotObject> hyp = dropDontCareHypotheses(gt, all_hyp, dont_care, threshold_);
  gt_total_ += gt.size();
  hyp_total_ += hyp.size();
  std::vector<int> hi;
  for (const MotObject& h : hyp) hi.push_back(denseIndex(hyp_index_, h.id));
  for (const MotObject& g : gt) {
    const int gi = denseIndex(gt_index_, g.id);
    for (std::size_t j = 0; j < hyp.size(); ++j)
      if ((g.p - hyp[j].p).norm() <= threshold_) ++together_[pairKey(gi, hi[j])];
  }
}

IdF1::Result IdF1::metrics() const {
  Result r;
  if (gt_total_ + hyp_total_ == 0) return r;
  if (!together_.empty()) {
    // Maximise the frames together: cost -IDTP, 0 for pairs never together (not forbidden: solveAssignment would
    // then maximise the number of pairs first, not the frames).
    Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(static_cast<long>(gt_index_.size()), static_cast<long>(hyp_index_.size()));
    for (const auto& [k, n] : together_) cost(keyGt(k), keyHyp(k)) = -double(n);
    const std::vector<int> match = solveAssignment(cost, kForbidden);
    for (std::size_t g = 0; g < match.size(); ++g)
      if (match[g] >= 0 && cost(static_cast<long>(g), match[g]) < 0.0) r.idtp += static_cast<std::size_t>(-cost(static_cast<long>(g), match[g]));
  }
  r.idf1 = 2.0 * double(r.idtp) / double(gt_total_ + hyp_total_);
  r.idp = hyp_total_ ? double(r.idtp) / double(hyp_total_) : 0.0;
  r.idr = gt_total_ ? double(r.idtp) / double(gt_total_) : 0.0;
  return r;
}

void Ospa::addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& all_hyp,
                    const std::vector<Eigen::Vector2d>& dont_care) {
  const std::vector<MotObject> hyp = dropDontCareHypotheses(gt, all_hyp, dont_care, dont_care_threshold_);
  const std::size_t n = std::max(gt.size(), hyp.size()), m = std::min(gt.size(), hyp.size());
  if (n == 0) return;
  double sum = std::pow(c_, p_) * double(n - m);
  if (m > 0) {
    Eigen::MatrixXd cost(static_cast<long>(gt.size()), static_cast<long>(hyp.size()));
    for (std::size_t i = 0; i < gt.size(); ++i)
      for (std::size_t j = 0; j < hyp.size(); ++j)
        cost(static_cast<long>(i), static_cast<long>(j)) = std::pow(std::min(c_, (gt[i].p - hyp[j].p).norm()), p_);
    const std::vector<int> match = solveAssignment(cost, kForbidden);
    for (std::size_t i = 0; i < gt.size(); ++i)
      if (match[i] >= 0) sum += cost(static_cast<long>(i), match[i]);
  }
  last_ = std::pow(sum / double(n), 1.0 / p_);
  sum_ += last_;
  ++frames_;
}

}  // namespace cairn::people_tracking
