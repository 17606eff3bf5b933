// Local SLAM (Cartographer's LocalTrajectoryBuilder2D, Hess et al. 2016 §IV): every scan is predicted from
// odometry (or a constant-velocity model), matched against the oldest active submap (optional real-time
// CSM, then the grid refiner with the prediction as motion prior), passed through a motion filter and, if it
// passes, inserted into the active submaps. Two overlapping submaps are active: a new one is started when the
// newest has scans_per_submap scans; the oldest is finished when it has 2 * scans_per_submap.
//
// Frames: local_pose = pose of the base in the local SLAM frame (= the first scan's base pose, or the
// first odometry pose if given). Submap::local_pose = grid frame in the local SLAM frame.
// Not thread-safe. Active submaps keep changing (shared_ptr<const Submap> views of the live objects) until
// they are finished; finished submaps never change again.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/correlative_matcher.hpp"
#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/grid_refiner.hpp"
#include "cairn/graph_slam/probability_grid.hpp"
#include "cairn/graph_slam/scan_filter.hpp"

namespace cairn::graph_slam {

struct LocalSlamOptions {
  ScanFilterOptions filter;
  /// Motion filter (Cartographer's defaults): a scan is inserted when the pose moved this much since the last
  /// inserted scan, or this much time passed.
  double motion_min_distance = 0.2;   ///< m
  double motion_min_angle = 0.0175;   ///< rad (1°)
  double motion_max_time = 5.0;       ///< s
  int scans_per_submap = 90;          ///< inserted scans per submap before the next one starts
  bool use_correlative = true;        ///< run real-time CSM before the refiner
  /// Real-time CSM window; the angular step is computed for points up to 10 m (farther points may move by
  /// up to range/10 cells per step: the refiner takes it from there), 3x fewer angles on 30 m scans.
  SearchWindow window{0.15, 0.35, 0.1, 0.1, 10.0};
  double min_correlative_score = 0.0;  ///< below: CSM result ignored, the refiner starts from the prediction
  RefineOptions refine;
  double grid_resolution = 0.05;      ///< m
  ProbabilityGridOptions grid;
  int min_points = 5;                 ///< scans with fewer returns are rejected
  double max_time_gap = 0.0;          ///< s: >0: a larger gap without odometry resets the velocity model
  /// Robustness and lost detection (ours; the thesis and Cartographer state no values — chosen on the Freiburg
  /// logs, where the refined score's 0.1 % quantile is 0.41–0.49 and its minimum 0.27, README "Front end"):
  /// a scan whose refined score is below recovery_score is searched again with the multi-resolution
  /// branch-and-bound matcher (Hess et al. 2016 §V-C) over recovery_window (wheel slip, a bump, a missed
  /// odometry message) and refined from its optimum; 0 disables.
  double recovery_score = 0.4;
  SearchWindow recovery_window{1.0, 0.6, 0.0, 0.0, 10.0};
  /// The recovered pose is taken only if its refined score beats the small-window one by this much: along a
  /// featureless corridor shifted poses score almost the same, and a marginal gain is no evidence.
  double recovery_min_gain = 0.1;
  int recovery_depth = 5;             ///< branch-and-bound levels (2^(depth-1) cells ≥ the window)
  /// A scan still below unmatched_score is held back (not inserted) until a scan matches again, then inserted
  /// as if nothing had happened (LocalResult::flushed); lost_scans consecutive unmatched scans report
  /// LocalResult::lost and are discarded (kidnapped, or the world is not where odometry says). 0 disables.
  double unmatched_score = 0.38;
  int lost_scans = 5;
  /// Scores are judged only against a submap with at least this many scans (a young submap scores low).
  int judge_min_submap_scans = 10;
};

struct LocalResult {
  double stamp = 0;
  Pose2 local_pose;                      ///< base in the local SLAM frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  ///< of the match (RefineResult::covariance)
  RangeData range_data;                  ///< base frame, filtered (what was / would be inserted)
  std::vector<Eigen::Vector2d> matching_points;  ///< downsampled points used for matching (base frame)
  bool inserted = false;                 ///< passed the motion filter and went into the submaps -> graph node
  std::vector<std::shared_ptr<const Submap>> insertion_submaps;  ///< the submaps it went into (if inserted)
  double match_score = 0;                ///< mean matching value after refinement (0 for the first scan)
  bool matched = false;                  ///< false for the very first scan (nothing to match against)
  bool recovered = false;  ///< the branch-and-bound recovery search moved the pose (recovery_score)
  /// Score below unmatched_score after recovery: held back, not inserted (yet); `flushed` of a later result
  /// or discarded when the robot is lost.
  bool unmatched = false;
  /// Unmatched and held back (lost_scans > 0): it comes back in a later result's `flushed`, or is discarded when
  /// the robot is lost. With lost detection off, unmatched scans are inserted at once and never held.
  bool held = false;
  /// lost_scans consecutive unmatched scans ended with this one. The caller decides (GraphSlam starts a new
  /// trajectory and searches globally); the counter restarts.
  bool lost = false;
  /// Held-back unmatched scans, in order, that went in now because this scan matched again (inserted = they
  /// passed the motion filter); the caller treats them as if they had come before this one.
  std::vector<LocalResult> flushed;
};

class LocalSlam {
 public:
  explicit LocalSlam(LocalSlamOptions o = {});

  /// odom: odometry pose of the base at scan time (std::nullopt: constant-velocity prediction from the last
  /// two matched poses). Never throws on bad scans: returns std::nullopt for a scan with too few valid points
  /// or with time going backwards (reason in lastError()).
  std::optional<LocalResult> addScan(double stamp, const RangeData& data, const std::optional<Pose2>& odom);

  std::vector<std::shared_ptr<const Submap>> activeSubmaps() const;    ///< 1-2, oldest first
  std::vector<std::shared_ptr<const Submap>> finishedSubmaps() const;  ///< all finished, in order
  /// Submaps finished since the last call (pollable; in order).
  std::vector<std::shared_ptr<const Submap>> takeNewlyFinished();
  /// Forgets the finished submaps (whoever took them keeps them alive): finishedSubmaps() is empty afterwards,
  /// so that a long run does not keep every submap it ever finished.
  void releaseFinished();

  const std::string& lastError() const { return last_error_; }
  const LocalSlamOptions& options() const { return options_; }
  /// Last matched pose, or nullopt before the first scan.
  std::optional<Pose2> lastPose() const { return last_pose_; }
  std::size_t scansAdded() const { return scans_; }
  std::size_t scansInserted() const { return inserted_; }

 private:
  struct ActiveMatch {
    Pose2 pose;  ///< local frame
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
    double score = 0;
    bool recovered = false, unmatched = false;
  };
  struct Held {
    LocalResult result;
    bool insert_it = false;  ///< the motion filter's decision when it came
  };
  /// Real-time CSM + refinement against the oldest active submap; the branch-and-bound recovery below
  /// recovery_score.
  ActiveMatch matchActive(const std::vector<Eigen::Vector2d>& pts, const Pose2& predicted) const;
  Pose2 predict(double stamp, const std::optional<Pose2>& odom) const;
  void insert(const RangeData& data, const Pose2& pose, LocalResult& r);

  LocalSlamOptions options_;
  std::vector<std::shared_ptr<Submap>> active_;
  std::vector<std::shared_ptr<const Submap>> finished_;
  std::size_t newly_finished_from_ = 0;
  std::string last_error_;
  std::optional<Pose2> last_pose_;
  std::optional<Pose2> last_odom_;
  double last_stamp_ = 0;
  bool have_stamp_ = false;
  // constant-velocity model (used without odometry)
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();  ///< body-frame (vx, vy, w)
  // motion filter
  std::optional<Pose2> last_inserted_pose_;
  double last_inserted_stamp_ = 0;
  std::size_t scans_ = 0, inserted_ = 0;
  std::vector<Held> held_;  ///< the current run of unmatched scans
  int next_submap_index_ = 0;
};

}  // namespace cairn::graph_slam
