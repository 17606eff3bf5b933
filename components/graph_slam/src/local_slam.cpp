// Local SLAM: prediction, scan-to-submap matching, motion filter, submap lifecycle (Hess et al. 2016 §IV).
#include "cairn/graph_slam/local_slam.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cairn::graph_slam {
namespace {

std::vector<Eigen::Vector2d> finiteOnly(const std::vector<Eigen::Vector2d>& pts) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(pts.size());
  for (const auto& p : pts) {
    if (p.allFinite()) out.push_back(p);
  }
  return out;
}

bool finitePose(const Pose2& p) { return p.t.allFinite() && std::isfinite(p.theta); }

}  // namespace

LocalSlam::LocalSlam(LocalSlamOptions o) : options_(std::move(o)) {
  options_.scans_per_submap = std::max(1, options_.scans_per_submap);
}

Pose2 LocalSlam::predict(double stamp, const std::optional<Pose2>& odom) const {
  if (!last_pose_) return odom ? *odom : Pose2{};
  if (odom && last_odom_) return compose(*last_pose_, compose(inverse(*last_odom_), *odom));
  // Constant velocity (body frame) since the last scan.
  double dt = stamp - last_stamp_;
  if (options_.max_time_gap > 0.0 && dt > options_.max_time_gap) dt = 0.0;
  Pose2 delta;
  delta.t = velocity_.head<2>() * dt;
  delta.theta = normalizeAngle(velocity_.z() * dt);
  return compose(*last_pose_, delta);
}

LocalSlam::ActiveMatch LocalSlam::matchActive(const std::vector<Eigen::Vector2d>& pts, const Pose2& predicted) const {
  const Submap& sm = *active_.front();
  const Pose2 prior = compose(inverse(sm.local_pose), predicted);
  Pose2 initial = prior;
  if (options_.use_correlative) {
    if (auto m = correlativeMatch(sm.grid, pts, prior, options_.window, options_.min_correlative_score)) initial = m->pose;
  }
  RefineResult ref = refine(sm.grid, pts, initial, prior, options_.refine);
  ActiveMatch out;
  const bool judged = sm.num_scans >= options_.judge_min_submap_scans;  // a young submap scores low
  if (judged && ref.score < options_.recovery_score) {
    // Multi-resolution search over a larger window (Hess et al. 2016 §V-C branch and bound on max-pooled
    // grids), only when the small-window match is poor: the active submap keeps changing, so its
    // precomputation is built here, for this scan (a few hundred µs), not kept.
    const BranchAndBoundMatcher bnb(sm.grid, options_.recovery_depth);
    if (auto m = bnb.match(pts, prior, options_.recovery_window, ref.score + options_.recovery_min_gain)) {
      // No odometry prior here: the prediction is what failed (weights as for loop-closure refinement).
      RefineOptions unanchored = options_.refine;
      unanchored.translation_weight = unanchored.rotation_weight = 1e-3;
      unanchored.degenerate_translation_weight = -1.0;
      const RefineResult again = refine(sm.grid, pts, m->pose, m->pose, unanchored);
      if (again.score >= ref.score + options_.recovery_min_gain) {
        ref = again;
        out.recovered = true;
      }
    }
  }
  out.unmatched = judged && ref.score < options_.unmatched_score;
  out.pose = compose(sm.local_pose, ref.pose);
  // Rotate the covariance from the grid frame into the local frame.
  Eigen::Matrix3d Rt = Eigen::Matrix3d::Identity();
  Rt.topLeftCorner<2, 2>() = rotation2(sm.local_pose.theta);
  out.covariance = Rt * ref.covariance * Rt.transpose();
  out.score = ref.score;
  return out;
}

std::optional<LocalResult> LocalSlam::addScan(double stamp, const RangeData& data, const std::optional<Pose2>& odom) {
  last_error_.clear();
  if (!std::isfinite(stamp)) {
    last_error_ = "LocalSlam::addScan: stamp is not finite";
    return std::nullopt;
  }
  if (have_stamp_ && stamp < last_stamp_) {
    std::ostringstream os;
    os.precision(17);
    os << "LocalSlam::addScan: time went backwards (stamp " << stamp << " < previous " << last_stamp_ << "); scan dropped";
    last_error_ = os.str();
    return std::nullopt;
  }
  std::optional<Pose2> od = odom;
  if (od && !finitePose(*od)) od.reset();  // unusable odometry: treated as missing
  LocalResult r;
  r.stamp = stamp;
  r.range_data.origin = data.origin.allFinite() ? data.origin : Eigen::Vector2d::Zero();
  r.range_data.returns = voxelFilter(finiteOnly(data.returns), options_.filter.voxel_size);
  r.range_data.misses = voxelFilter(finiteOnly(data.misses), options_.filter.voxel_size);
  if (static_cast<int>(r.range_data.returns.size()) < options_.min_points) {
    std::ostringstream os;
    os << "LocalSlam::addScan: scan at " << stamp << " has " << r.range_data.returns.size()
       << " valid returns (< min_points " << options_.min_points << "); scan dropped";
    last_error_ = os.str();
    return std::nullopt;
  }
  r.matching_points = adaptiveVoxelFilter(r.range_data.returns, options_.filter);
  if (r.matching_points.empty()) r.matching_points = r.range_data.returns;

  const Pose2 predicted = predict(stamp, od);
  Pose2 pose = predicted;
  if (!active_.empty()) {
    ActiveMatch m = matchActive(r.matching_points, predicted);
    if (!m.unmatched && !held_.empty()) {
      // The unmatched run ended: the held-back scans go in as they would have (same order, same motion-filter
      // decisions), and this scan is matched again against the grid they changed — the same result as if they
      // had never been held back.
      for (Held& h : held_) {
        if (h.insert_it) insert(h.result.range_data, h.result.local_pose, h.result);
        r.flushed.push_back(std::move(h.result));
      }
      held_.clear();
      m = matchActive(r.matching_points, predicted);
    }
    pose = m.pose;
    r.covariance = m.covariance;
    r.match_score = m.score;
    r.recovered = m.recovered;
    r.unmatched = m.unmatched;
    r.matched = true;
  } else {
    r.covariance = Eigen::Matrix3d::Identity() * 1e-6;
  }
  r.local_pose = pose;

  // Motion filter (Cartographer's MotionFilter).
  bool insert_it = !last_inserted_pose_;
  if (!insert_it) {
    const Pose2 d = compose(inverse(*last_inserted_pose_), pose);
    insert_it = stamp - last_inserted_stamp_ > options_.motion_max_time || d.t.norm() > options_.motion_min_distance ||
                std::abs(d.theta) > options_.motion_min_angle;
  }
  if (r.unmatched && options_.lost_scans > 0) {
    // Held back (not inserted) until the run of unmatched scans ends: a kidnapped robot must not write the new
    // place into the old submaps, while an isolated bad scan changes nothing (it is inserted with the next one).
    if (insert_it) {
      last_inserted_pose_ = pose;  // the motion filter runs as if it had been inserted
      last_inserted_stamp_ = stamp;
    }
    r.held = true;
    held_.push_back({r, insert_it});
    if (static_cast<int>(held_.size()) >= options_.lost_scans) {
      r.lost = true;
      held_.clear();
    }
  } else if (insert_it) {
    insert(r.range_data, pose, r);
  }

  // Constant-velocity model from consecutive poses.
  if (last_pose_ && stamp > last_stamp_) {
    const Pose2 d = compose(inverse(*last_pose_), pose);
    const double dt = stamp - last_stamp_;
    velocity_ = Eigen::Vector3d(d.t.x() / dt, d.t.y() / dt, d.theta / dt);
  }
  last_pose_ = pose;
  last_odom_ = od;
  last_stamp_ = stamp;
  have_stamp_ = true;
  ++scans_;
  return r;
}

void LocalSlam::insert(const RangeData& data, const Pose2& pose, LocalResult& r) {
  const int spm = options_.scans_per_submap;
  auto newSubmap = [&] {
    auto sm = std::make_shared<Submap>(Submap{Pose2{pose.t, 0.0}, ProbabilityGrid(options_.grid_resolution, options_.grid),
                                              0, false, next_submap_index_++});
    active_.push_back(std::move(sm));
  };
  if (active_.empty()) newSubmap();
  for (auto& sm : active_) {
    sm->grid.insert(data, compose(inverse(sm->local_pose), pose));
    ++sm->num_scans;
    r.insertion_submaps.push_back(sm);
  }
  if (active_.front()->num_scans >= 2 * spm) {
    active_.front()->finished = true;
    active_.front()->grid.crop();
    finished_.push_back(active_.front());
    active_.erase(active_.begin());
  }
  if (active_.empty() || active_.back()->num_scans >= spm) newSubmap();
  r.inserted = true;
  last_inserted_pose_ = pose;
  last_inserted_stamp_ = r.stamp;
  ++inserted_;
}

std::vector<std::shared_ptr<const Submap>> LocalSlam::activeSubmaps() const {
  return {active_.begin(), active_.end()};
}

std::vector<std::shared_ptr<const Submap>> LocalSlam::finishedSubmaps() const { return finished_; }

std::vector<std::shared_ptr<const Submap>> LocalSlam::takeNewlyFinished() {
  std::vector<std::shared_ptr<const Submap>> out(finished_.begin() + static_cast<std::ptrdiff_t>(newly_finished_from_),
                                                 finished_.end());
  newly_finished_from_ = finished_.size();
  return out;
}

void LocalSlam::releaseFinished() {
  finished_.clear();
  newly_finished_from_ = 0;
}

}  // namespace cairn::graph_slam
