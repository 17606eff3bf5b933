// Multi-person tracker: one EKF with a constant-velocity model per person (Stüde §2.1.3 after [LGA15]),
// association by global nearest neighbour (Hungarian on Mahalanobis costs with chi-square gating) or by JPDA,
// logic-based initiation/confirmation/deletion. Tracks live in the odom (or map) frame: each scan's detections
// are transformed with the sensor pose at the scan stamp, which compensates the robot's own motion.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "cairn/people_tracking/detector.hpp"
#include "cairn/people_tracking/fusion.hpp"
#include "cairn/people_tracking/scan.hpp"
#include "cairn/people_tracking/static_map.hpp"

namespace cairn::people_tracking {

enum class Association { kGnn, kJpda };
const char* toString(Association a);
Association associationFromString(const std::string& s);  // "gnn" | "jpda"; throws InputError

struct TrackerParams {
  Association association = Association::kGnn;
  // Constant-velocity model, x = [px py vx vy]; continuous white-noise acceleration with spectral density
  // process_noise (m^2/s^3): Q = q [dt^3/3 I, dt^2/2 I; dt^2/2 I, dt I]. 0.15 (with the maneuver gate below)
  // instead of 0.3: 108 bench runs 424 -> 398 switches, with the static map 426 -> 395, furnished worlds -11 %
  // (docs/benchmarks.md "Process noise and the maneuver gate"). Our choice; the thesis states no value.
  double process_noise = 0.15;
  // Maneuver gate (GNN; with JPDA for tracks with nothing in their gate; our choice, after the covariance
  // resetting on a detected maneuver of Bar-Shalom, Li & Kirubarajan 2001, ch. 11): a confirmed track with no
  // detection in its gate takes the best detection within the gate of S + maneuver_gate_sigma^2 I that no other
  // track's gate holds (not a single leg); its covariance grows by maneuver_gate_sigma^2 in position and
  // (maneuver_gate_sigma / maneuver_gate_time)^2 in velocity before the update (the velocity of a person who
  // turned, started or stopped is what the filter got wrong) and its adaptive noise is raised. A person alone who
  // turns 90 deg in 0.5 s at 1.3 m/s kept the track 35 of 50 times with q 0.15 (46 with q 0.3) without it, 50 of
  // 50 with it (test ManeuverGateTest.KeepsAPersonWhoTurnsStartsOrStops). 0 disables.
  double maneuver_gate_sigma = 0.15;  // m
  double maneuver_gate_time = 0.3;    // s
  double initial_velocity_sigma = 0.8;  // m/s, velocity std of a new track
  double gate_chi2 = 9.21;              // 99 % gate, chi-square with 2 dof
  // Tentative -> confirmed (published) after this many associated scans. 3 vs 2 (ETH/hotel/zara01 x
  // static/circle x seeds 1-3): IDSW 358 -> 287 (a new track in a group often starts on legs of two people and
  // settles on one only after a scan or two), FN 15.7k -> 20.9k, FP 2313 -> 1877; 4: 253 switches, MOTA 0.901.
  int confirm_hits = 3;
  // ... and, if > 0, once its track score reaches this: the log-likelihood ratio "a person, not clutter" of its
  // detections since birth (Blackman & Popoli 1999 §6.2, a sequential probability ratio test): each update adds
  // ln(P_D / (2π sqrt|S| β)) − d²/2 (d² the innovation's Mahalanobis distance, S its covariance, P_D =
  // detection_probability, β = clutter_density), each scan without one ln(1 − P_D) (at most ln 1e-3).
  // Detections that keep to a constant-velocity path confirm the track in confirm_hits scans; a track that took
  // legs of two people, or clutter, needs more. Wald's threshold ln((1 − β_miss) / α): 8 is α ≈ 4e-4 false confirmations at 10 % missed
  // people (our choice, measured on the bench against 0 / 6 … 13, docs/benchmarks.md "Track score"). 0 = hits only.
  double confirm_score = 8.0;
  double tentative_timeout = 0.4;       // s without an update deletes a tentative track
  double delete_timeout = 1.5;          // s without an update deletes a confirmed track
  double max_position_sigma = 1.5;      // m, tracks whose position std grows beyond this are deleted
  double min_init_distance = 0.45;      // m, no new track this close to an existing confirmed track
  double min_detection_confidence = 0.0;
  double publish_coast_time = 0.25;     // s, outputTracks() omits confirmed tracks not updated for longer
  double max_dt = 2.0;                  // s, larger forward jumps reset the tracker
  double confidence_gain = 0.3;         // confidence <- confidence + gain * (hit - confidence)
  // JPDA
  double detection_probability = 0.9;
  double clutter_density = 0.02;  // false detections per m^2 (within the gates)
  int jpda_max_events = 20000;    // larger gating clusters fall back to GNN
  // Track-aware leg pairing (updateLegs): each track may take up to two legs whose Mahalanobis distance to its
  // predicted position, with the leg's spread around the body centre added to the covariance, is within
  // leg_gate_chi2. Confirmed tracks choose first (Hungarian with a "no leg" option per slot); legs nobody took
  // are paired closest-first into new person hypotheses.
  double leg_spread_sigma = 0.20;  // m, std of a leg centre around the body centre (hip offset + stride)
  double leg_gate_chi2 = 9.21;     // 99 % gate, 2 dof
  // A track's recent detection record in the leg cost (updateLegs): a leg costs confidence_cost * (1 - confidence)
  // more for a track whose confidence (the moving average of its associations, confidence_gain) is low, i.e. whose
  // person has been missing in the last scans — usually hidden behind someone, whose legs its gate then reaches.
  // A prior on whether the track gets a leg now, like a per-track detection probability (our choice; the linear
  // form and the value are measured, docs/benchmarks.md "Track confidence in the leg cost"). 0 disables.
  double confidence_cost = 2.0;
  // Legs swing along the walking direction but stay at the hip width across it: for a track moving faster than
  // leg_spread_min_speed the spread is leg_spread_sigma along the velocity and leg_spread_lateral_sigma across it,
  // so a coasting track does not reach sideways into the legs of someone walking next to it. Lateral 0.13 m (the
  // sim's walkers: hip half-width 0.07-0.12 m plus the pair noise) measured against 0.12 / 0.14 / 0.16 / 0.18 m:
  // docs/benchmarks.md "Lateral leg spread".
  double leg_spread_lateral_sigma = 0.13;  // m
  double leg_spread_min_speed = 0.3;       // m/s
  // Re-identification: a confirmed track deleted less than reid_window ago gives its id to a new track when it
  // is confirmed within reid_gate_chi2 of the deleted track's prediction (constant velocity, process noise).
  double reid_window = 6.0;     // s, 0 disables (with reid_max_distance 1 m, 6 vs 3 s: 326 vs 332 switches, 18 runs)
  double reid_gate_chi2 = 9.21;
  // m: and within this distance of it. The prediction's gate grows with the time since deletion (to metres after
  // a few seconds), and CLEAR MOT does not count an id handed to a person seen for the first time, so without a
  // bound re-identification passed ids on to newcomers (54-run sweep: IDF1 0.748 vs 0.946 with 1 m).
  double reid_max_distance = 1.0;
  // Occlusion-aware coasting (updateLegs with a scan): the beams towards a track that got no leg tell whether
  // its person is hidden behind a nearer return (occluded), or whether the beams pass through the spot (free
  // space: the person is not there), or hit something there that was not classified as a leg (missed).
  double visibility_radius = 0.3;       // m, beams within this radius around the predicted position are checked
  double occluded_coast_time = 1.0;     // s, outputTracks() keeps occluded confirmed tracks this long
  double occluded_delete_timeout = 3.0; // s, deletion of a track occluded since its last update (or standing)
  int free_space_delete_scans = 2;      // consecutive free-space scans delete a track
  // Standing people (our choice; the theses state no model for them): a confirmed track whose speed after each
  // update has stayed below standing_speed for standing_time is *standing*. While it gets no detection it is
  // predicted in place — velocity 0 with std standing_speed / 3, no position-velocity correlation, position
  // variance growing by standing_position_noise per second — instead of by the constant-velocity model, whose
  // process noise alone widens a hidden person's position std to ~0.6 m within 2 s (q 0.15), far enough to take
  // the legs of whoever stands next to them. The next update continues with the constant-velocity model. A
  // standing track is deleted after occluded_delete_timeout, as an occluded one (free space still deletes it).
  // Hotel circle runs, seeds 1-27, ids undone: 119 -> 79 switches, all 162 runs 408 -> 370, raw 629 -> 591
  // (docs/benchmarks.md "Standing people"). standing_time 0 disables.
  double standing_time = 1.0;             // s
  double standing_speed = 0.3;            // m/s
  double standing_position_noise = 0.02;  // m^2/s
  // updateLegs with detections of other sources: their pairing with the persons made from legs. Gated by
  // Mahalanobis distance (a camera's range error is long along the line of sight; Stüde's Euclidean 0.5 m nearest
  // pairs, FusionParams{}, paired such detections with the wrong person: bench --camera 360, 18 runs, IDSW 673 vs
  // 268, FP 14 778 vs 2627).
  FusionParams fusion{1.5, 9.21};
  // Group-aware split (updateLegs): a confirmed track that takes two legs while at least two more legs nobody
  // took lie in its gate, for this many consecutive scans, is re-paired closest-first; it keeps the pair nearest
  // its prediction and every other pair starts a track (min_init_distance does not apply). 0 disables.
  // 1 vs 0: ETH/hotel/zara01 x static/circle x seeds 1-3: IDSW 631 -> 628, FP 2140 -> 2121, FN 26146 -> 26001.
  int split_scans = 1;
  // Joint leg pairing (updateLegs, GNN): each gating cluster of tracks and legs is solved with the exact pair
  // likelihood — a track's two legs share its centre, so its position uncertainty widens the legs' midpoint, not
  // their separation (tracker.cpp jointPairs) — by branch and bound with at most this many search nodes per cluster
  // (larger clusters keep the per-leg Hungarian solution). 0 = per-leg Hungarian only; JPDA always pairs per leg.
  // 54 bench runs: switches 758 -> 692 (seeds 10-18: 729 -> 651); mean search 2-3 nodes per cluster, largest seen
  // 5905 (18 tracks).
  int joint_pairs_max_nodes = 100000;
  // Gait-aware single-leg update (updateLegs): a track moving faster than leg_spread_min_speed that takes only
  // one leg is updated with the leg's covariance grown by this std along its walking direction: a leg swings
  // about +-0.3 m fore and aft of the body (0.21 m std), so alone it says little about the body along the walk.
  // 0 disables. ETH/hotel/zara01 x static/circle x seeds 1-3: IDSW 628 -> 554 (0.3), 563 (0.2), 556 (0.45).
  double single_leg_stride_sigma = 0.3;
  // Interacting multiple models (IMM, Blom & Bar-Shalom 1988): every track runs two constant-velocity filters,
  // mode 0 with process_noise (steady walking) and mode 1 with maneuver_process_noise (starting, stopping,
  // turning), mixed by a Markov chain with the given switching rates (per second; the per-scan probability is
  // 1 - exp(-rate dt)). Gating and the published state use the moment-matched mixture, so a person who turns or
  // speeds up keeps the track instead of leaving a gate sized for straight walking. 0 = one mode (plain EKF).
  double maneuver_process_noise = 0.0;  // m^2/s^3
  double maneuver_rate = 0.5;           // 1/s, walking -> maneuver
  double maneuver_end_rate = 2.0;       // 1/s, maneuver -> walking
  // Adaptive process noise (GNN, one mode; Bar-Shalom, Li & Kirubarajan 2001, §11.2 "adjustable level process
  // noise"): each track keeps an exponentially smoothed normalized innovation squared (NIS, expected 2 for a
  // consistent filter with 2-D measurements) of its updates; while it is above adaptive_nis_threshold the track is
  // predicted with adaptive_noise_gain x process_noise. A person who speeds up or turns (or an annotation that jumps:
  // docs/benchmarks.md "Annotation jitter") gives a run of large innovations; a single swinging leg does not, as
  // its covariance already holds the stride. Unlike the IMM's per-scan mode likelihoods it needs several surprising
  // updates in a row. 0 disables. 54 bench runs: switches 804 -> 758 (seeds 10-18: 780 -> 729), IDF1 0.950 -> 0.948.
  double adaptive_nis_threshold = 3.0;
  double adaptive_noise_gain = 30.0;
  double adaptive_nis_smoothing = 0.5;  // weight of the newest NIS in the average
  // With a static map (setStaticMap, updateLegs): legs within this distance of an occupied cell are dropped.
  double static_map_margin = 0.1;  // m
};

// Why a track got no leg in the last scan (updateLegs with a scan; kUnknown without one).
enum class Visibility { kDetected, kUnknown, kMissed, kOccluded, kFreeSpace };

struct Track {
  int id = 0;
  Eigen::Vector4d state = Eigen::Vector4d::Zero();           // px py vx vy (tracking frame)
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Identity();  // of state
  // IMM modes (TrackerParams::maneuver_process_noise > 0): per-mode state and covariance and the mode
  // probabilities; state/covariance above are their moment-matched mixture. With one mode only [0] is used.
  std::array<Eigen::Vector4d, 2> mode_state{Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero()};
  std::array<Eigen::Matrix4d, 2> mode_covariance{Eigen::Matrix4d::Identity(), Eigen::Matrix4d::Identity()};
  Eigen::Vector2d mode_probability{1.0, 0.0};
  double stamp = 0.0;        // time of the state
  double first_stamp = 0.0;  // initiation time
  double last_update = 0.0;  // last associated detection
  int hits = 0;
  bool confirmed = false;
  double score = 0.0;  // track score while tentative (TrackerParams::confirm_score)
  double confidence = 0.0;       // [0, 1], moving average of association success
  double leg_separation = 0.0;   // m, moving average from paired-leg detections (0 if never paired)
  Visibility visibility = Visibility::kUnknown;  // in the last scan
  int free_space_scans = 0;      // consecutive scans whose beams passed through the track
  int split_evidence = 0;        // consecutive scans with four or more legs in its gate (split_scans)
  bool occluded_since_update = false;  // every scan since the last update saw it occluded
  double slow_since = -1.0;  // stamp since which every update left it slower than standing_speed (-1: not slow)
  double nis = 2.0;  // smoothed normalized innovation squared of its updates (TrackerParams::adaptive_*)

  [[nodiscard]] Eigen::Vector2d position() const { return state.head<2>(); }
  [[nodiscard]] Eigen::Vector2d velocity() const { return state.tail<2>(); }
  [[nodiscard]] Eigen::Matrix2d positionCovariance() const { return covariance.topLeftCorner<2, 2>(); }
  [[nodiscard]] double age() const { return stamp - first_stamp; }
};

struct TrackerStatus {
  bool reset = false;  // the tracker dropped all tracks before processing this input
  std::string reason;  // why ("time went backwards", "time jump of N s")
};

class PeopleTracker {
 public:
  explicit PeopleTracker(TrackerParams params = {});

  // Detections in the sensor frame; sensor_pose is the sensor in the tracking frame at `stamp`.
  TrackerStatus update(double stamp, const std::vector<PersonDetection>& detections, const Pose2& sensor_pose);
  // Detections already in the tracking frame.
  TrackerStatus updateInFrame(double stamp, const std::vector<PersonDetection>& detections);
  // Leg detections (sensor frame) paired into persons with the help of the predicted tracks, so that the legs of
  // people walking side by side are not paired across them; `pairing` supplies max_leg_pair_distance,
  // sigma_pair, sigma_single and single_leg_min_confidence. Then associated as update() does.
  // With `scan` (the scan the legs came from), tracks without legs are classified as occluded / free space /
  // missed (Track::visibility): occluded ones coast longer, free-space ones are hidden and deleted.
  // `others`: person detections of other sources (e.g. a camera) at the same stamp, already in the tracking
  // frame. Each is fused with the nearest person made from the legs (fusion.hpp, Stüde §2.1.3; within
  // TrackerParams::fusion) and keeps that person's track; the rest are associated and start tracks like the
  // persons made from legs nobody took.
  TrackerStatus updateLegs(double stamp, const std::vector<LegDetection>& legs, const Pose2& sensor_pose,
                           const DetectorParams& pairing, const LaserScan* scan = nullptr,
                           const std::vector<PersonDetection>& others = {});

  [[nodiscard]] const std::vector<Track>& tracks() const { return tracks_; }  // tentative and confirmed
  [[nodiscard]] std::vector<Track> confirmedTracks() const;
  // What a consumer should see: confirmed tracks updated within publish_coast_time (coasting tracks are kept
  // internally through short occlusions, but are not reported as people).
  [[nodiscard]] std::vector<Track> outputTracks() const;
  [[nodiscard]] const TrackerParams& params() const { return params_; }
  void reset();
  // Static occupancy (static_map.hpp): updateLegs drops legs on it; nullptr removes it. Kept across reset().
  void setStaticMap(std::shared_ptr<const StaticMap> map) { static_map_ = std::move(map); }
  [[nodiscard]] bool hasStaticMap() const { return static_map_ != nullptr; }

 private:
  TrackerStatus checkTime(double stamp);
  void predict(double stamp);
  void associate(const std::vector<PersonDetection>& dets, std::vector<bool>& used);
  std::vector<PersonDetection> pairWithTracks(const std::vector<LegDetection>& legs, const DetectorParams& pairing,
                                              std::vector<int>& det_track);
  void splitGroups(const std::vector<LegDetection>& legs, const DetectorParams& pairing, const Eigen::MatrixXd& cost,
                   const std::vector<std::size_t>& rows, const std::vector<std::size_t>& cols,
                   std::vector<std::vector<std::size_t>>& track_legs, std::vector<bool>& leg_used,
                   std::vector<PersonDetection>& split);
  void associateGnn(const std::vector<PersonDetection>& dets, std::vector<bool>& det_used, bool confirmed_stage);
  void maneuverGate(const std::vector<PersonDetection>& dets, std::vector<bool>& used,
                    const std::vector<std::size_t>& rows);
  void associateJpda(const std::vector<PersonDetection>& dets, std::vector<bool>& det_used);
  void applyUpdate(Track& t, const PersonDetection& d);
  void initiate(const std::vector<PersonDetection>& dets, const std::vector<bool>& det_used);
  void prune();
  Eigen::Matrix2d legSpread(const Track& t) const;
  // A leg's position about the track's centre: the gait spread plus the detector's pair noise (G in jointPairs).
  Eigen::Matrix2d legCovariance(const Track& t, const DetectorParams& pairing) const;
  // What a leg costs a track on top of its likelihood (TrackerParams::confidence_cost), per leg.
  [[nodiscard]] double legConfidenceCost(const Track& t) const;
  void jointPairs(const std::vector<LegDetection>& legs, const DetectorParams& pairing, const Eigen::MatrixXd& cost,
                  const std::vector<std::size_t>& rows, const std::vector<std::size_t>& cols, std::vector<int>& match) const;
  void reidentify(std::size_t new_track);
  // Within static_map_margin of an occupied cell of the static map (false without a map).
  [[nodiscard]] bool onStaticMap(const Eigen::Vector2d& p) const;
  void classifyVisibility(const LaserScan& scan, const Pose2& sensor_pose);

  struct Deleted {
    Track track;     // state at its last prediction before deletion
    double deleted;  // stamp of deletion
  };
  std::vector<Deleted> deleted_;  // confirmed tracks deleted within reid_window
  std::vector<Eigen::Vector2d> split_births_;  // this scan's detections split off a track (initiate() ignores min_init_distance)

  TrackerParams params_;
  std::shared_ptr<const StaticMap> static_map_;
  std::vector<Track> tracks_;
  std::vector<bool> updated_;  // per track, associated in the current scan
  double last_stamp_ = 0.0;
  bool has_stamp_ = false;
  int next_id_ = 1;
};

}  // namespace cairn::people_tracking
