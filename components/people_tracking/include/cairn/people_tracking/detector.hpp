// Scan -> leg detections (segmentation + features + classifier) -> person detections (leg pairing).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "cairn/people_tracking/classifier.hpp"
#include "cairn/people_tracking/motion_evidence.hpp"
#include "cairn/people_tracking/segmentation.hpp"

namespace cairn::people_tracking {

struct LegDetection {
  Eigen::Vector2d position;  // sensor frame, estimated leg centre
  double confidence = 0.0;   // classifier score
  double width = 0.0;        // cluster width (m)
  // Share of the cluster's points an earlier scan saw as free space (motion_evidence.hpp); 0 when not evaluated
  // (no history, or a score that passes the plain thresholds anyway); below moving_fraction it is a lower bound
  // (the count stops once the cluster cannot reach it).
  double moving = 0.0;
};

// A person hypothesis in the frame of its source (sensor frame from the detector; odom/map after transform).
struct PersonDetection {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity() * 0.01;
  double confidence = 0.0;
  double leg_separation = 0.0;  // m, 0 when only one leg / merged legs were seen
  int legs = 0;                 // 2: paired legs, 1: single cluster
  int source = 0;               // detection source id (fusion)
};

// The detector's segmentation: SegmentationParams' defaults except min_points 1. A leg hit by one or two beams (at
// 6-8 m, or mostly hidden behind another person's leg) is no shape for the classifier, which learns from clusters of
// >= 3 points (training keeps SegmentationParams' default), but where it scores as a leg or the beams passed
// there a moment ago (motion evidence) it keeps the track that expects it. 54 bench runs (ETH/hotel/zara01 x
// static/circle x seeds 1-9): switches 692 -> 447 (docs/benchmarks.md "Legs of one and two beams", also for the
// furnished worlds).
inline SegmentationParams detectorSegmentation() {
  SegmentationParams s;
  s.min_points = 1;
  return s;
}

struct DetectorParams {
  SegmentationParams segmentation = detectorSegmentation();
  double min_leg_confidence = 0.5;     // classifier score to accept a cluster as a leg (persons, new tracks)
  // Track-supported detection: detectLegs also returns clusters scored down to this, for PeopleTracker::updateLegs,
  // which lets them update existing tracks only; pairLegs (persons, track initiation) ignores legs below
  // min_leg_confidence. A value >= min_leg_confidence turns it off. ETH/hotel/zara01 x static/circle x seeds
  // 1-3 (with single_leg_stride_sigma 0.3): IDSW 554 -> 358, FN 26260 -> 15661, FP 1915 -> 2313 (0.2; 0.1: 343 /
  // 14188 / 2584; 0.0: 297 / 12486 / 4445).
  double track_leg_confidence = 0.2;
  // With a static map attached to the tracker (detectLegs' `static_map`), this replaces track_leg_confidence: most
  // low-scored clusters without a map are wall and furniture returns (wall ends, walls seen at grazing angles), which
  // keep false tracks alive, and the map drops those before they reach a track (PeopleTracker::updateLegs). ETH/
  // hotel/zara01 x static/circle x seeds 1-9 with --static-map: 0.2 -> 0.0 takes IDSW 446 -> 372, FP 3929 -> 3991,
  // FN 44325 -> 40568 (without a map 0.0 gives 372 switches but FP 6512 -> 17461). Our choice (docs/benchmarks.md
  // "Weak legs with a static map").
  double track_leg_confidence_with_map = 0.0;
  // Moving clusters (detectLegs with motion evidence; LegDetection::moving >= moving_fraction) pass with lower
  // scores: down to moving_track_leg_confidence for updating tracks, down to moving_min_leg_confidence for
  // persons and new tracks, also as an unpaired leg (instead of single_leg_min_confidence). Furniture and walls are
  // never moving, so these do not let them in (docs/benchmarks.md "Motion evidence"). A threshold >= the plain one
  // turns that part off. moving_min_leg_confidence 0.5 -> 0.0 (with moving single legs and
  // MotionEvidenceParams::min_free_scans 2): 54 bench runs IDSW 447 -> 389 (held-out seeds 441 -> 382), FP +0.2 %,
  // FN -25 %; with --static-map 372 -> 293 (docs/benchmarks.md "Moving legs start tracks"). The leg classifier
  // scores 1-2-point clusters low whatever they are; their motion says they are legs. Our choice.
  double moving_fraction = 0.5;
  double moving_track_leg_confidence = 0.0;
  double moving_min_leg_confidence = 0.0;
  // Clusters standing where the beams went through within the last MotionEvidenceParams::memory seconds
  // (MotionEvidence::crossedBefore at the cluster's surface point: not the static background, which is never
  // crossed) update tracks from this score, as every cluster does with a static map (track_leg_confidence_with_map):
  // what the map gives, learned from the scans. Persons and new tracks keep min_leg_confidence. A value >=
  // track_leg_confidence turns it off. 54 bench runs without a map: IDSW 351 -> 252 (the true map in its place:
  // 246), FP +1.3 %, FN -12 % (docs/benchmarks.md "Free-space memory"). Our choice.
  double crossed_track_leg_confidence = 0.0;
  double max_range = 10.0;             // m, clusters beyond are ignored
  // Clusters of fewer points than the classifier learned from (SegmentationParams{}.min_points, 3) closer than this
  // are dropped: at 3 m a leg spans about 6 beams at 0.33 deg, so one or two are a sliver of a hidden leg or
  // clutter. Without it the mask-bench guide (0.7 m ahead) was lost in 2 of 20 seeds (tracked 60 / 74 % of the
  // tour instead of 90 %; with 1.5 m still one seed at 79 %); the people bench: 443 -> 447 switches (54 runs).
  // Our choice.
  double small_cluster_min_range = 3.0;  // m
  double max_leg_width = 0.45;         // m, wider clusters are not legs (also rejects most walls cheaply)
  // Two legs in one cluster (gapSplitIndex): a cluster at least split_min_width wide whose largest step between
  // consecutive returns is >= split_gap_ratio x the median of the others and >= split_min_gap_beams beam spacings
  // becomes two legs, each with the cluster's score and motion. The legs of one person, one partly behind the
  // other, merge into one cluster in 4-8 % of the leg clusters on the replays; the tracker then saw one "leg" at
  // the person's centre, and its joint pairing let a track take that and a neighbour's leg as a pair. With the
  // static map, 54 bench runs: 293 -> 245 switches (held-out seeds 283 -> 258), FN -9 %, FP flat (docs/benchmarks.md
  // "Two legs in one cluster"). split_min_width 0.2 m lies above the widest single leg seen (the simulator's legs
  // have radius 0.05-0.08 m, chord <= 0.16 m; 0.12-0.15 m split single legs and multiplied false positives);
  // split_gap_ratio 2.5 and split_min_gap_beams 2.5 are our choice (measured with the map, ids undone: ratio
  // 2 / 2.5 / 3 gave 166 / 169 / 178 switches). A split_min_width above max_leg_width turns it off.
  double split_min_width = 0.2;        // m
  double split_gap_ratio = 2.5;
  double split_min_gap_beams = 2.5;
  double leg_center_offset = 0.04;     // m, leg centre lies behind the visible surface along the beam
  double max_leg_pair_distance = 0.8;  // m, two legs closer than this form a person
  double single_leg_min_confidence = 0.6;  // an unpaired leg cluster needs this score to become a person
  double sigma_pair = 0.06;            // m, position std of a paired-leg person (both axes)
  double sigma_single = 0.15;          // m, position std of a single-cluster person (other leg unseen/merged)
};

class PersonDetector {
 public:
  PersonDetector(std::shared_ptr<const LegClassifier> classifier, DetectorParams params = {});

  // Throws InputError on malformed scans. Optional outputs: leg detections.
  std::vector<PersonDetection> detect(const LaserScan& scan, std::vector<LegDetection>* legs = nullptr) const;
  // Leg detections only (sensor frame), for PeopleTracker::updateLegs. Throws InputError on malformed scans.
  // With `motion` (the history of earlier scans) and the sensor pose in its frame at the scan stamp, clusters
  // scored below the plain thresholds get LegDetection::moving and pass with the moving_* thresholds, and those
  // standing where the beams went through earlier (its free-space memory) with crossed_track_leg_confidence. The caller
  // adds the scan to `motion` afterwards. `static_map`: the tracker the legs go to has a static map
  // (PeopleTracker::hasStaticMap), so track_leg_confidence_with_map replaces track_leg_confidence.
  [[nodiscard]] std::vector<LegDetection> detectLegs(const LaserScan& scan, const MotionEvidence* motion = nullptr,
                                                     const Pose2& sensor_pose = {}, bool static_map = false) const;
  [[nodiscard]] const DetectorParams& params() const { return params_; }

 private:
  std::shared_ptr<const LegClassifier> classifier_;
  DetectorParams params_;
};

// A person between two legs (covariance widened along the pair axis) and a person at one unpaired leg.
PersonDetection personFromLegs(const LegDetection& a, const LegDetection& b, const DetectorParams& params);
PersonDetection personFromLeg(const LegDetection& leg, const DetectorParams& params);

// Whether a leg may form persons and start tracks (min_leg_confidence, or moving_min_leg_confidence when moving).
bool isPersonLeg(const LegDetection& leg, const DetectorParams& params);
// Whether a leg may form persons and start tracks by its motion (moving >= moving_fraction and score >=
// moving_min_leg_confidence), also alone (pairLegs: instead of single_leg_min_confidence).
bool isMovingPersonLeg(const LegDetection& leg, const DetectorParams& params);

// Greedy closest-first pairing of legs into persons (each leg used once; legs below min_leg_confidence are
// skipped); exposed for tests and other sources.
std::vector<PersonDetection> pairLegs(const std::vector<LegDetection>& legs, const DetectorParams& params);

// The detections moved from a frame into the one where that frame has `pose` (positions and covariances).
std::vector<PersonDetection> transformDetections(std::vector<PersonDetection> detections, const Pose2& pose);

}  // namespace cairn::people_tracking
