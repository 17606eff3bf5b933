// Tracking metrics beside CLEAR MOT (clear_mot.hpp), for point objects on the ground plane:
//
// HOTA (Luiten et al., "HOTA: A Higher Order Metric for Evaluating Multi-Object Tracking", IJCV 2021). For each
// localisation threshold alpha = 0.05, 0.10, ..., 0.95 a ground-truth object and a hypothesis may be matched in a
// frame if their similarity S = max(0, 1 - d / zero_distance) is >= alpha; matching maximises (in this order) the
// number of matches, the pair's alignment A_max (the Ass-IoU the pair would have if matched in every frame where
// S >= alpha) and S — the paper's matching score 1/eps + A_max + eps*S. Then
//   DetA = TP / (TP + FN + FP),  AssA = mean over TP of Ass-IoU(g, h) = TPA / (TPA + FNA + FPA),
//   HOTA = sqrt(DetA * AssA),    LocA = mean S over TP,
// each averaged over the 19 thresholds (LocA over those with a match: it says how close the matches are). An ID switch halfway through a track costs AssA ~ 0.5 on that track,
// whatever the track's length, so HOTA weighs a switch by how much of the tracks it confuses; CLEAR MOT counts
// events. With zero_distance = 2 x the CLEAR MOT threshold, alpha = 0.5 matches at the CLEAR MOT threshold.
//
// IDF1 (Ristani et al., "Performance Measures and a Data Set for Multi-Target, Multi-Camera Tracking", ECCV
// workshops 2016): each ground-truth trajectory is assigned to at most one hypothesis trajectory and vice versa
// (Hungarian over whole trajectories) so that the number of frames in which the assigned pair is within the
// match threshold (IDTP) is largest; IDF1 = 2 IDTP / (ground-truth frames + hypothesis frames). Unlike CLEAR
// MOT's ID switches, which only count a person changing tracks, it also charges a track that carries one id
// over several people.
//
// OSPA (Schuhmacher, Vo & Vo, IEEE TSP 2008): per frame, with cut-off c and order p,
//   d = ( (min over assignments of sum min(c, |x - y|)^p + c^p (n - m)) / n )^(1/p),  n = max(|X|,|Y|), m = min;
// a set distance (localisation and cardinality errors in metres, identities not used), averaged over the frames
// in which anything was present.
//
// All three apply the don't-care rule first (dropDontCareHypotheses, as CLEAR MOT does); the bench instead gives them
// the hypotheses CLEAR MOT kept (ClearMot::lastHypotheses), so the rule runs once per frame.
#pragma once

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "cairn/people_tracking/clear_mot.hpp"

namespace cairn::people_tracking {

struct HotaMetrics {
  static constexpr int kAlphas = 19;  // alpha = 0.05 * (k + 1)
  static constexpr std::size_t kHalf = 9;  // alpha = 0.5
  double hota = 0.0, deta = 0.0, assa = 0.0, loca = 0.0;  // means over the alphas (LocA: those with a match)
  std::array<double, kAlphas> hota_alpha{}, deta_alpha{}, assa_alpha{}, loca_alpha{};
  [[nodiscard]] static double alpha(int k) { return 0.05 * (k + 1); }
};

class Hota {
 public:
  // zero_distance: d at which the similarity reaches 0; dont_care_threshold: the don't-care rule's distance.
  explicit Hota(double zero_distance = 1.0, double dont_care_threshold = 0.5);
  void addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                const std::vector<Eigen::Vector2d>& dont_care = {});
  [[nodiscard]] HotaMetrics metrics() const;

 private:
  struct Pair {
    int g, h;   // dense indices
    double s;   // similarity > 0
  };
  double zero_distance_, dont_care_threshold_;
  std::unordered_map<int, int> gt_index_, hyp_index_;
  std::vector<std::size_t> gt_frames_, hyp_frames_;  // frames each object is present in
  std::array<std::unordered_map<std::uint64_t, std::size_t>, HotaMetrics::kAlphas> potential_;  // S >= alpha
  std::vector<std::vector<Pair>> frames_;  // per frame, the pairs with S > 0
  std::size_t gt_total_ = 0, hyp_total_ = 0;
};

class IdF1 {
 public:
  explicit IdF1(double threshold = 0.5) : threshold_(threshold) {}
  void addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                const std::vector<Eigen::Vector2d>& dont_care = {});
  struct Result {
    double idf1 = 0.0, idp = 0.0, idr = 0.0;  // IDF1, ID precision IDTP / hyp frames, ID recall IDTP / gt frames
    std::size_t idtp = 0;
  };
  [[nodiscard]] Result metrics() const;

 private:
  double threshold_;
  std::unordered_map<int, int> gt_index_, hyp_index_;
  std::unordered_map<std::uint64_t, std::size_t> together_;  // (gt, hyp) -> frames within the threshold
  std::size_t gt_total_ = 0, hyp_total_ = 0;
};

class Ospa {
 public:
  explicit Ospa(double cutoff = 1.0, double order = 1.0, double dont_care_threshold = 0.5)
      : c_(cutoff), p_(order), dont_care_threshold_(dont_care_threshold) {}
  void addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                const std::vector<Eigen::Vector2d>& dont_care = {});
  // Mean OSPA distance (m) over the frames with at least one object or hypothesis; 0 if there was none.
  [[nodiscard]] double mean() const { return frames_ ? sum_ / double(frames_) : 0.0; }
  [[nodiscard]] double last() const { return last_; }

 private:
  double c_, p_, dont_care_threshold_;
  double sum_ = 0.0, last_ = 0.0;
  std::size_t frames_ = 0;
};

}  // namespace cairn::people_tracking
