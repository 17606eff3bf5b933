// CLEAR MOT metrics (Bernardin & Stiefelhagen 2008): per frame, correspondences from the previous frame are
// kept while within the match threshold, the rest are assigned optimally (Hungarian on distances); an ID switch
// is counted when a ground-truth object is matched to a different hypothesis than at its last match.
// MOTA = 1 - (FN + FP + IDSW) / GT, MOTP = mean distance of matches. Not part of CLEAR MOT, counted beside it:
// id_transfers, the mirror image of a switch — a hypothesis matched to a different object than at its last match
// (one track id carried over to another person, which CLEAR MOT does not charge).
#pragma once

#include <Eigen/Core>
#include <map>
#include <vector>

namespace cairn::people_tracking {

struct MotObject {
  int id = 0;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
};

struct MotMetrics {
  std::size_t frames = 0, gt = 0, matches = 0, fp = 0, fn = 0, id_switches = 0, gt_tracks = 0, ignored = 0,
              id_transfers = 0;
  double distance_sum = 0.0;
  [[nodiscard]] double mota() const { return gt ? 1.0 - double(fn + fp + id_switches) / double(gt) : 0.0; }
  [[nodiscard]] double motp() const { return matches ? distance_sum / double(matches) : 0.0; }
  [[nodiscard]] double idSwitchesPer100Tracks() const { return gt_tracks ? 100.0 * double(id_switches) / double(gt_tracks) : 0.0; }
};

// One correspondence of the last frame: ground-truth id, hypothesis id, and the hypothesis the object was matched
// to at its previous match if this one is an ID switch (-1 otherwise).
struct MotCorrespondence {
  int gt = 0, hyp = 0, switched_from = -1;
};

// MOTChallenge's distractor preprocessing, shared by the scorers: hypotheses and all objects, counted (gt) or not
// (dont_care), are matched optimally (Hungarian on distances within threshold); the hypotheses matched to a
// don't-care object are removed. Returns the kept hypotheses; *ignored (if given) counts the removed ones.
std::vector<MotObject> dropDontCareHypotheses(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                                              const std::vector<Eigen::Vector2d>& dont_care, double threshold,
                                              std::size_t* ignored = nullptr);

class ClearMot {
 public:
  explicit ClearMot(double threshold = 0.5) : threshold_(threshold) {}
  // dont_care: positions of people that exist but do not count (out of range or line of sight). As in the
  // MOTChallenge evaluation's distractor preprocessing, hypotheses are first matched optimally (Hungarian,
  // threshold) to all objects, counted and don't-care; those matched to a don't-care object are removed from
  // the frame (counted as `ignored`, neither FP nor matches) before the CLEAR MOT matching.
  void addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                const std::vector<Eigen::Vector2d>& dont_care = {});
  [[nodiscard]] MotMetrics metrics() const;
  // The correspondences of the last addFrame (for dumps and switch analysis: one scorer, no re-matching).
  [[nodiscard]] const std::vector<MotCorrespondence>& lastFrame() const { return frame_; }
  // The hypotheses of the last addFrame that the don't-care rule kept (for other scorers of the same frame).
  [[nodiscard]] const std::vector<MotObject>& lastHypotheses() const { return kept_; }

 private:
  double threshold_;
  MotMetrics m_;
  std::map<int, int> last_match_;  // gt id -> hypothesis id at its last match
  std::map<int, int> current_;     // gt id -> hypothesis id matched in the previous frame
  std::map<int, int> hyp_last_;    // hypothesis id -> gt id at its last match
  std::map<int, bool> seen_gt_;
  std::vector<MotCorrespondence> frame_;
  std::vector<MotObject> kept_;
};

}  // namespace cairn::people_tracking
