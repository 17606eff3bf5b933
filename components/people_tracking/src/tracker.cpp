#include "cairn/people_tracking/tracker.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <utility>

#include "cairn/people_tracking/assignment.hpp"
#include "cairn/people_tracking/param_ranges.hpp"

namespace cairn::people_tracking {

const char* toString(Association a) { return a == Association::kGnn ? "gnn" : "jpda"; }

Association associationFromString(const std::string& s) {
  if (s == "gnn") return Association::kGnn;
  if (s == "jpda") return Association::kJpda;
  throw InputError("unknown association '" + s + "' (gnn|jpda)");
}

namespace {
// Every numeric parameter against its range (param_ranges.hpp): a negative process noise or a zero gate would
// otherwise give NaN costs and covariances instead of an error.
void checkParams(const TrackerParams& p) {
  const std::pair<const char*, double> values[] = {
      {"tracker.process_noise", p.process_noise},
      {"tracker.maneuver_process_noise", p.maneuver_process_noise},
      {"tracker.maneuver_rate", p.maneuver_rate},
      {"tracker.maneuver_end_rate", p.maneuver_end_rate},
      {"tracker.initial_velocity_sigma", p.initial_velocity_sigma},
      {"tracker.gate_chi2", p.gate_chi2},
      {"tracker.confirm_hits", p.confirm_hits},
      {"tracker.confirm_score", p.confirm_score},
      {"tracker.tentative_timeout", p.tentative_timeout},
      {"tracker.delete_timeout", p.delete_timeout},
      {"tracker.max_position_sigma", p.max_position_sigma},
      {"tracker.min_init_distance", p.min_init_distance},
      {"tracker.publish_coast_time", p.publish_coast_time},
      {"tracker.max_dt", p.max_dt},
      {"tracker.detection_probability", p.detection_probability},
      {"tracker.clutter_density", p.clutter_density},
      {"tracker.jpda_max_events", p.jpda_max_events},
      {"tracker.min_detection_confidence", p.min_detection_confidence},
      {"tracker.confidence_gain", p.confidence_gain},
      {"tracker.confidence_cost", p.confidence_cost},
      {"tracker.maneuver_gate_sigma", p.maneuver_gate_sigma},
      {"tracker.maneuver_gate_time", p.maneuver_gate_time},
      {"tracker.leg_spread_sigma", p.leg_spread_sigma},
      {"tracker.leg_spread_lateral_sigma", p.leg_spread_lateral_sigma},
      {"tracker.leg_spread_min_speed", p.leg_spread_min_speed},
      {"tracker.leg_gate_chi2", p.leg_gate_chi2},
      {"tracker.reid_window", p.reid_window},
      {"tracker.reid_gate_chi2", p.reid_gate_chi2},
      {"tracker.reid_max_distance", p.reid_max_distance},
      {"tracker.visibility_radius", p.visibility_radius},
      {"tracker.occluded_coast_time", p.occluded_coast_time},
      {"tracker.occluded_delete_timeout", p.occluded_delete_timeout},
      {"tracker.free_space_delete_scans", p.free_space_delete_scans},
      {"tracker.standing_time", p.standing_time},
      {"tracker.standing_speed", p.standing_speed},
      {"tracker.standing_position_noise", p.standing_position_noise},
      {"tracker.split_scans", p.split_scans},
      {"tracker.joint_pairs_max_nodes", p.joint_pairs_max_nodes},
      {"tracker.single_leg_stride_sigma", p.single_leg_stride_sigma},
      {"static_map.margin", p.static_map_margin},
      {"fusion.max_pair_distance", p.fusion.max_pair_distance},
      {"fusion.gate_chi2", p.fusion.gate_chi2},
  };
  for (const auto& [name, value] : values) {
    const ParamRange r = paramRange(name);
    if (!(value >= r.lo && value <= r.hi))
      throw InputError(std::string("tracker parameter ") + name + " must be in " + rangeText(r) + ", got " + numberText(value));
  }
}
}  // namespace

PeopleTracker::PeopleTracker(TrackerParams params) : params_(params) { checkParams(params_); }

void PeopleTracker::reset() {
  tracks_.clear();
  deleted_.clear();
  has_stamp_ = false;
}

std::vector<Track> PeopleTracker::confirmedTracks() const {
  std::vector<Track> out;
  for (const auto& t : tracks_)
    if (t.confirmed) out.push_back(t);
  return out;
}

std::vector<Track> PeopleTracker::outputTracks() const {
  std::vector<Track> out;
  for (const auto& t : tracks_) {
    if (!t.confirmed || t.visibility == Visibility::kFreeSpace) continue;
    const double coast = t.stamp - t.last_update;
    if (coast <= params_.publish_coast_time || (t.occluded_since_update && coast <= params_.occluded_coast_time))
      out.push_back(t);
  }
  return out;
}

TrackerStatus PeopleTracker::update(double stamp, const std::vector<PersonDetection>& detections,
                                    const Pose2& sensor_pose) {
  return updateInFrame(stamp, transformDetections(detections, sensor_pose));
}

namespace {
struct Innovation {
  Eigen::Vector2d nu;
  Eigen::Matrix2d S;
  double d2 = 0.0;
};
// Constant-velocity prediction with continuous white-noise acceleration (spectral density q):
// Q = q [dt^3/3 I, dt^2/2 I; dt^2/2 I, dt I].
void predictCv(Eigen::Vector4d& x, Eigen::Matrix4d& P, double dt, double q) {
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F(0, 2) = F(1, 3) = dt;
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
  const double a = q * dt * dt * dt / 3.0, b = q * dt * dt / 2.0, c = q * dt;
  Q(0, 0) = Q(1, 1) = a;
  Q(0, 2) = Q(2, 0) = Q(1, 3) = Q(3, 1) = b;
  Q(2, 2) = Q(3, 3) = c;
  x = F * x;
  P = F * P * F.transpose() + Q;
}

bool immOn(const TrackerParams& p) { return p.maneuver_process_noise > 0.0; }

// The track's state and covariance as the moment-matched mixture of its modes.
void combineModes(Track& t, int modes) {
  if (modes == 1) {
    t.state = t.mode_state[0];
    t.covariance = t.mode_covariance[0];
    return;
  }
  t.state = t.mode_probability[0] * t.mode_state[0] + t.mode_probability[1] * t.mode_state[1];
  t.covariance.setZero();
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector4d dx = t.mode_state[k] - t.state;
    t.covariance += t.mode_probability[k] * (t.mode_covariance[k] + dx * dx.transpose());
  }
}

// A confirmed track whose updates have left it slower than standing_speed for standing_time (TrackerParams).
bool standing(const Track& t, const TrackerParams& p) {
  return p.standing_time > 0.0 && t.confirmed && t.slow_since >= 0.0 && t.last_update - t.slow_since >= p.standing_time;
}

// Prediction to `stamp`: one constant-velocity filter, or the IMM cycle (mode mixing by the Markov chain, then
// each mode predicted with its own process noise).
void predictTrack(Track& t, double stamp, const TrackerParams& p) {
  const double dt = stamp - t.stamp;
  if (dt <= 0.0) return;
  const bool coasting = t.last_update < t.stamp;  // no detection in the last scan
  t.stamp = stamp;
  if (coasting && standing(t, p)) {
    // Predicted in place (TrackerParams::standing_*): every mode, so that the IMM's mixing keeps it there too.
    const double sv = p.standing_speed / 3.0;
    for (int k = 0; k < 2; ++k) {
      t.mode_state[k].tail<2>().setZero();
      t.mode_covariance[k].topRightCorner<2, 2>().setZero();
      t.mode_covariance[k].bottomLeftCorner<2, 2>().setZero();
      t.mode_covariance[k].bottomRightCorner<2, 2>() = sv * sv * Eigen::Matrix2d::Identity();
      t.mode_covariance[k].topLeftCorner<2, 2>() += p.standing_position_noise * dt * Eigen::Matrix2d::Identity();
    }
    combineModes(t, immOn(p) ? 2 : 1);
    return;
  }
  if (!immOn(p)) {
    // Adaptive process noise (TrackerParams::adaptive_*): a run of surprising updates raises the noise level.
    const bool adapt = p.adaptive_nis_threshold > 0.0 && t.nis > p.adaptive_nis_threshold;
    predictCv(t.mode_state[0], t.mode_covariance[0], dt, adapt ? p.process_noise * p.adaptive_noise_gain : p.process_noise);
    combineModes(t, 1);
    return;
  }
  Eigen::Matrix2d pi;  // pi(i, j): probability of mode i -> mode j within dt
  const double a = 1.0 - std::exp(-p.maneuver_rate * dt), b = 1.0 - std::exp(-p.maneuver_end_rate * dt);
  pi << 1.0 - a, a, b, 1.0 - b;
  const Eigen::Vector2d c = pi.transpose() * t.mode_probability;  // predicted mode probabilities
  std::array<Eigen::Vector4d, 2> x0;
  std::array<Eigen::Matrix4d, 2> P0;
  for (int j = 0; j < 2; ++j) {
    x0[j].setZero();
    P0[j].setZero();
    if (!(c[j] > 0.0)) {
      x0[j] = t.mode_state[j];
      P0[j] = t.mode_covariance[j];
      continue;
    }
    for (int i = 0; i < 2; ++i) x0[j] += pi(i, j) * t.mode_probability[i] / c[j] * t.mode_state[i];
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector4d dx = t.mode_state[i] - x0[j];
      P0[j] += pi(i, j) * t.mode_probability[i] / c[j] * (t.mode_covariance[i] + dx * dx.transpose());
    }
  }
  const double q[2] = {p.process_noise, p.maneuver_process_noise};
  for (int j = 0; j < 2; ++j) {
    t.mode_state[j] = x0[j];
    t.mode_covariance[j] = P0[j];
    predictCv(t.mode_state[j], t.mode_covariance[j], dt, q[j]);
  }
  t.mode_probability = c / c.sum();
  combineModes(t, 2);
}

// Kalman update of one mode with a position measurement (Joseph form); returns the measurement's log-likelihood.
double updateMode(Eigen::Vector4d& x, Eigen::Matrix4d& P, const PersonDetection& d) {
  const Eigen::Vector2d nu = d.position - x.head<2>();
  const Eigen::Matrix2d S = P.topLeftCorner<2, 2>() + d.covariance;
  const Eigen::Matrix2d Si = S.inverse();
  const Eigen::Matrix<double, 4, 2> K = P.leftCols<2>() * Si;
  x += K * nu;
  Eigen::Matrix<double, 2, 4> H = Eigen::Matrix<double, 2, 4>::Zero();
  H(0, 0) = H(1, 1) = 1.0;
  const Eigen::Matrix4d IKH = Eigen::Matrix4d::Identity() - K * H;
  P = IKH * P * IKH.transpose() + K * d.covariance * K.transpose();
  return -0.5 * nu.dot(Si * nu) - 0.5 * std::log(S.determinant()) - std::log(2.0 * M_PI);
}

// Gating clusters: tracks [0, nt) and detections [0, nd) connected through gated(i, j) (union-find), those with at
// least one of each; tracks and detections ascending, clusters ordered by their first track. Association decisions
// in one cluster cannot affect another (JPDA's joint events, the joint leg pairing's search).
struct GatingCluster {
  std::vector<std::size_t> tracks, dets;
};
std::vector<GatingCluster> gatingClusters(std::size_t nt, std::size_t nd,
                                          const std::function<bool(std::size_t, std::size_t)>& gated) {
  std::vector<std::size_t> parent(nt + nd);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto root = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < nt; ++i)
    for (std::size_t j = 0; j < nd; ++j)
      if (gated(i, j)) parent[root(i)] = root(nt + j);
  std::vector<GatingCluster> out;
  std::map<std::size_t, std::size_t> index;  // root -> position in out
  for (std::size_t i = 0; i < nt; ++i) {
    const auto [it, fresh] = index.emplace(root(i), out.size());
    if (fresh) out.emplace_back();
    out[it->second].tracks.push_back(i);
  }
  for (std::size_t j = 0; j < nd; ++j) {
    const auto it = index.find(root(nt + j));
    if (it != index.end()) out[it->second].dets.push_back(j);
  }
  std::erase_if(out, [](const GatingCluster& c) { return c.dets.empty(); });
  return out;
}

Innovation innovation(const Track& t, const PersonDetection& d) {
  Innovation in;
  in.nu = d.position - t.state.head<2>();
  in.S = t.covariance.topLeftCorner<2, 2>() + d.covariance;
  in.d2 = in.nu.dot(in.S.ldlt().solve(in.nu));
  return in;
}

// The log-likelihood ratio of a detection taken by the track against clutter, ln(P_D N(nu; 0, S) / beta): the track
// score's increment (TrackerParams::confirm_score; Blackman & Popoli 1999 §6.2) and the JPDA's event weight.
double scoreIncrement(const Innovation& in, const TrackerParams& p) {
  return std::log(p.detection_probability / (2.0 * M_PI * p.clutter_density)) - 0.5 * std::log(in.S.determinant()) -
         0.5 * in.d2;
}
}  // namespace

TrackerStatus PeopleTracker::checkTime(double stamp) {
  TrackerStatus status;
  if (!std::isfinite(stamp)) throw InputError("tracker update with a non-finite stamp");
  if (has_stamp_ && stamp < last_stamp_) {
    status.reset = true;
    status.reason = "time went backwards by " + std::to_string(last_stamp_ - stamp) + " s";
  } else if (has_stamp_ && stamp - last_stamp_ > params_.max_dt) {
    status.reset = true;
    status.reason = "time jump of " + std::to_string(stamp - last_stamp_) + " s";
  }
  if (status.reset) reset();
  predict(stamp);
  last_stamp_ = stamp;
  has_stamp_ = true;
  updated_.assign(tracks_.size(), false);
  for (Track& t : tracks_) t.visibility = Visibility::kUnknown;
  return status;
}

void PeopleTracker::associate(const std::vector<PersonDetection>& dets, std::vector<bool>& used) {
  if (params_.association == Association::kGnn) {
    associateGnn(dets, used, true);  // confirmed tracks first: tentative ones cannot steal their detections
    associateGnn(dets, used, false);
  } else {
    associateJpda(dets, used);
  }
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    t.confidence += params_.confidence_gain * ((updated_[i] ? 1.0 : 0.0) - t.confidence);
    if (updated_[i]) {
      if (t.velocity().norm() >= params_.standing_speed) t.slow_since = -1.0;
      else if (t.slow_since < 0.0) t.slow_since = last_stamp_;
      t.visibility = Visibility::kDetected;
      t.free_space_scans = 0;
      t.occluded_since_update = true;  // vacuous until the first miss
    } else {
      t.free_space_scans = t.visibility == Visibility::kFreeSpace ? t.free_space_scans + 1 : 0;
      t.occluded_since_update = t.occluded_since_update && t.visibility == Visibility::kOccluded;
    }
    // A miss costs ln(1 - P_D), at most ln(1e-3): with P_D = 1 one miss would otherwise keep a track from ever being
    // confirmed.
    if (!updated_[i] && !t.confirmed) t.score += std::log(std::max(1.0 - params_.detection_probability, 1e-3));
    if (updated_[i] && !t.confirmed && t.hits >= params_.confirm_hits &&
        (params_.confirm_score <= 0.0 || t.score >= params_.confirm_score)) {
      t.confirmed = true;
      if (params_.reid_window > 0.0) reidentify(i);
    }
  }
  initiate(dets, used);
  prune();
}

TrackerStatus PeopleTracker::updateInFrame(double stamp, const std::vector<PersonDetection>& detections) {
  const TrackerStatus status = checkTime(stamp);
  std::vector<PersonDetection> dets;
  for (const auto& d : detections)
    if (d.confidence >= params_.min_detection_confidence && d.position.allFinite() && d.covariance.allFinite())
      dets.push_back(d);
  std::vector<bool> used(dets.size(), false);
  associate(dets, used);
  return status;
}

TrackerStatus PeopleTracker::updateLegs(double stamp, const std::vector<LegDetection>& legs,
                                        const Pose2& sensor_pose, const DetectorParams& pairing,
                                        const LaserScan* scan, const std::vector<PersonDetection>& others) {
  const TrackerStatus status = checkTime(stamp);
  std::vector<LegDetection> in_frame;
  in_frame.reserve(legs.size());
  for (const auto& l : legs) {
    if (!l.position.allFinite()) continue;
    const Eigen::Vector2d p = sensor_pose.transform(l.position);
    // Legs on the static map are parts of it (wall ends, furniture seen edge-on): neither start nor feed tracks.
    if (onStaticMap(p)) continue;
    in_frame.push_back({p, l.confidence, l.width, l.moving});
  }
  std::vector<int> det_track;
  std::vector<PersonDetection> dets = pairWithTracks(in_frame, pairing, det_track);
  if (!others.empty()) {
    // Other sources (Stüde §2.1.3): nearest pairs fused by the information-weighted average; a fused person keeps
    // the track its legs were given to, the others' remaining detections go through association and initiation.
    std::vector<PersonDetection> rest;
    for (const PersonDetection& d : others)
      if (d.position.allFinite() && d.covariance.allFinite() && !onStaticMap(d.position))
        rest.push_back(d);
    std::vector<bool> fused(rest.size(), false);
    for (const auto& [i, j] : nearestPairs(dets, rest, params_.fusion)) {
      dets[i] = fusePair(dets[i], rest[j]);
      fused[j] = true;
    }
    for (std::size_t j = 0; j < rest.size(); ++j)
      if (!fused[j]) {
        dets.push_back(rest[j]);
        det_track.push_back(-1);
      }
  }
  std::vector<bool> used(dets.size(), false);
  for (std::size_t j = 0; j < dets.size(); ++j)
    used[j] = dets[j].confidence < params_.min_detection_confidence;
  if (params_.association == Association::kGnn) {
    // The pairing already decided which track explains which legs.
    for (std::size_t j = 0; j < dets.size(); ++j) {
      if (det_track[j] < 0 || used[j]) continue;
      const auto i = static_cast<std::size_t>(det_track[j]);
      applyUpdate(tracks_[i], dets[j]);
      updated_[i] = true;
      used[j] = true;
    }
  }
  if (scan) classifyVisibility(*scan, sensor_pose);
  associate(dets, used);
  return status;
}

// Negative information from the scan for tracks that got no leg: look at the beams within visibility_radius of
// the predicted position. Most of them ending well before it (or too close to measure): occluded. All of them
// passing behind it (or without return within a range_max that reaches behind it): nobody is there. Otherwise
// something is there that was not detected as legs. NaN readings, and beams without return when the track is
// beyond the laser's reach, say nothing.
void PeopleTracker::classifyVisibility(const LaserScan& scan, const Pose2& sensor_pose) {
  const double rho = params_.visibility_radius;
  const long n = static_cast<long>(scan.ranges.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    if (updated_[i]) continue;
    const Eigen::Vector2d p = sensor_pose.inverseTransform(t.position());
    const double r = p.norm();
    Visibility vis = Visibility::kUnknown;
    if (r > rho) {
      const double half = std::asin(rho / r);
      const double bearing = std::atan2(p.y(), p.x());
      const long lo = static_cast<long>(std::ceil((bearing - half - scan.angle_min) / scan.angle_increment));
      const long hi = static_cast<long>(std::floor((bearing + half - scan.angle_min) / scan.angle_increment));
      int front = 0, behind = 0, total = 0;
      const bool reaches_behind = scan.range_max >= r + rho;
      for (long k = std::max(0L, lo); k <= std::min(n - 1, hi); ++k) {
        const auto b = static_cast<std::size_t>(k);
        const float range = scan.ranges[b];
        if (scan.valid(b)) {
          if (range > r + rho) ++behind;
          else if (range < r - rho) ++front;
        } else if (scan.beyondRange(b)) {
          if (!reaches_behind) continue;
          ++behind;
        } else if (std::isnan(range)) {
          continue;
        } else {
          ++front;  // below range_min (or -inf): something right in front of the sensor
        }
        ++total;
      }
      if (total >= 2) {
        if (2 * front >= total) vis = Visibility::kOccluded;
        else if (behind == total) vis = Visibility::kFreeSpace;
        else vis = Visibility::kMissed;
      }
    }
    t.visibility = vis;
  }
}

// Track-aware leg pairing: rows are two leg slots per track, columns the legs plus one "no leg" column per slot
// (cost = gate), so the Hungarian solution gives every track the legs that fit it best jointly with its
// neighbours. Confirmed tracks choose before tentative ones.
std::vector<PersonDetection> PeopleTracker::pairWithTracks(const std::vector<LegDetection>& legs,
                                                           const DetectorParams& pairing,
                                                           std::vector<int>& det_track) {
  const std::size_t nl = legs.size();
  std::vector<bool> leg_used(nl, false), gated_by_confirmed(nl, false);
  std::vector<std::vector<std::size_t>> track_legs(tracks_.size());
  std::vector<PersonDetection> split;
  split_births_.clear();
  const double spread2 = params_.leg_spread_sigma * params_.leg_spread_sigma;
  constexpr double kForbidden = 1e9;
  const double log_det0 = 2.0 * std::log(spread2 + pairing.sigma_pair * pairing.sigma_pair);
  for (const bool confirmed_stage : {true, false}) {
    std::vector<std::size_t> rows, cols;
    for (std::size_t i = 0; i < tracks_.size(); ++i)
      if (tracks_[i].confirmed == confirmed_stage) rows.push_back(i);
    for (std::size_t j = 0; j < nl; ++j)
      if (!leg_used[j]) cols.push_back(j);
    if (rows.empty() || cols.empty()) continue;
    const long nr = static_cast<long>(2 * rows.size()), nc = static_cast<long>(cols.size());
    Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(nr, nc + nr, kForbidden);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const Track& t = tracks_[rows[r]];
      const Eigen::Matrix2d S = t.positionCovariance() + legCovariance(t, pairing);
      const Eigen::Matrix2d Si = S.inverse();
      // Negative log-likelihood: the log-determinant keeps uncertain (coasting) tracks from taking legs that a
      // well-localised neighbour explains. "No leg" costs the gate plus the log-determinant of a perfectly
      // localised track, the same for every track (a per-row constant would not change the assignment). A track
      // that missed its legs lately pays legConfidenceCost more per leg.
      const double per_leg = std::log(S.determinant()) + legConfidenceCost(t);
      for (std::size_t c = 0; c < cols.size(); ++c) {
        const Eigen::Vector2d nu = legs[cols[c]].position - t.position();
        const double d2 = nu.dot(Si * nu);
        if (d2 > params_.leg_gate_chi2) continue;
        cost(static_cast<long>(2 * r), static_cast<long>(c)) = d2 + per_leg;
        cost(static_cast<long>(2 * r + 1), static_cast<long>(c)) = d2 + per_leg;
      }
      for (long k = 0; k < 2; ++k)
        cost(static_cast<long>(2 * r) + k, nc + static_cast<long>(2 * r) + k) = params_.leg_gate_chi2 + log_det0;
    }
    std::vector<int> match = solveAssignment(cost, kForbidden);
    // GNN only: with JPDA it cut switches by 2 % but added 26 % false positives (docs/benchmarks.md).
    if (params_.association == Association::kGnn && params_.joint_pairs_max_nodes > 0)
      jointPairs(legs, pairing, cost, rows, cols, match);
    // Legs inside a confirmed track's gate that it did not take (its third leg, or a leg too far from its
    // partner) are not evidence of a new person: starting tracks on them splits one person into two.
    if (confirmed_stage)
      for (long r = 0; r < nr; r += 2)
        for (long c = 0; c < nc; ++c)
          if (cost(r, c) < kForbidden) gated_by_confirmed[cols[static_cast<std::size_t>(c)]] = true;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      std::vector<std::size_t>& mine = track_legs[rows[r]];
      for (std::size_t k = 0; k < 2; ++k) {
        const int m = match[2 * r + k];
        if (m >= 0 && m < nc) mine.push_back(cols[static_cast<std::size_t>(m)]);
      }
      // Two legs too far apart for one person: keep the one closer to the prediction.
      if (mine.size() == 2 &&
          (legs[mine[0]].position - legs[mine[1]].position).norm() > pairing.max_leg_pair_distance) {
        const Eigen::Vector2d p = tracks_[rows[r]].position();
        if ((legs[mine[0]].position - p).norm() > (legs[mine[1]].position - p).norm()) std::swap(mine[0], mine[1]);
        mine.pop_back();
      }
      for (std::size_t j : mine) leg_used[j] = true;
    }
    if (confirmed_stage && params_.split_scans > 0) splitGroups(legs, pairing, cost, rows, cols, track_legs, leg_used, split);
  }
  std::vector<PersonDetection> out;
  det_track.clear();
  for (const PersonDetection& d : split) {
    out.push_back(d);
    det_track.push_back(-1);
  }
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const auto& mine = track_legs[i];
    if (mine.empty()) continue;
    if (mine.size() == 2) {
      out.push_back(personFromLegs(legs[mine[0]], legs[mine[1]], pairing));
    } else {
      out.push_back(personFromLeg(legs[mine[0]], pairing));
      // One leg of a walking person is the stance foot (standing still) or the swinging one (twice the body's
      // speed): along the walking direction it says little about the body centre, so a track seeing only one
      // leg for a few scans neither stops on the stance foot nor jumps ahead with the swing.
      const Track& t = tracks_[i];
      const double speed = t.velocity().norm();
      if (params_.single_leg_stride_sigma > 0.0 && speed > params_.leg_spread_min_speed) {
        const Eigen::Vector2d u = t.velocity() / speed;
        out.back().covariance += params_.single_leg_stride_sigma * params_.single_leg_stride_sigma * u * u.transpose();
      }
    }
    det_track.push_back(static_cast<int>(i));
  }
  std::vector<LegDetection> rest;
  for (std::size_t j = 0; j < nl; ++j)
    if (!leg_used[j] && !gated_by_confirmed[j]) rest.push_back(legs[j]);  // pairLegs skips weak legs
  for (const PersonDetection& d : pairLegs(rest, pairing)) {
    out.push_back(d);
    det_track.push_back(-1);
  }
  return out;
}

// Joint leg assignment with the exact pair likelihood (TrackerParams::joint_pairs_max_nodes). The per-leg costs
// treat a track's two legs as independent given its predicted centre c ~ N(c^, P): each leg ~ N(c^, P + G), G the
// leg spread about the body (plus the pair noise). But both legs share the one centre, so the midpoint is
// m ~ N(c^, P + G/2) and the separation s ~ N(0, 2G), independent of P; the per-leg model puts P/2 into the
// midpoint and 2P into the separation instead. For a well-localised track (P -> 0) both give the same cost (the
// map (a, b) -> (m, s) has unit Jacobian); for a young or coasting track (large P) the per-leg model accepts one
// leg of each of two people walking side by side as a "pair" and the track settles between them. A pair cost is
// not a sum of per-leg costs, so each gating cluster (tracks and legs connected by gates) is solved exactly by
// branch and bound over the tracks' options (no leg, one leg, a pair within max_leg_pair_distance), cheapest
// first; a cluster needing more than max_nodes search nodes keeps the Hungarian solution in `match`.
void PeopleTracker::jointPairs(const std::vector<LegDetection>& legs, const DetectorParams& pairing,
                               const Eigen::MatrixXd& cost, const std::vector<std::size_t>& rows,
                               const std::vector<std::size_t>& cols, std::vector<int>& match) const {
  constexpr double kForbidden = 1e9;
  const std::size_t nc = cols.size();
  auto gated = [&](std::size_t r, std::size_t c) { return cost(static_cast<long>(2 * r), static_cast<long>(c)) < kForbidden; };
  const double no_leg = cost(0, static_cast<long>(nc));  // the same for every slot
  struct Option {
    double cost;
    int a, b;  // leg columns, -1 = none
  };
  for (const GatingCluster& cluster : gatingClusters(rows.size(), nc, gated)) {
    const std::vector<std::size_t>& tr = cluster.tracks;  // rows
    const std::vector<std::size_t>& lg = cluster.dets;    // columns
    std::vector<std::vector<Option>> options(tr.size());
    for (std::size_t k = 0; k < tr.size(); ++k) {
      const std::size_t r = tr[k];
      const Track& t = tracks_[rows[r]];
      const Eigen::Matrix2d G = legCovariance(t, pairing);
      const Eigen::Matrix2d M = t.positionCovariance() + 0.5 * G, Sep = 2.0 * G;
      const Eigen::Matrix2d Mi = M.inverse(), Sepi = Sep.inverse();
      const double log_dets =
          std::log(M.determinant()) + std::log(Sep.determinant()) + 2.0 * legConfidenceCost(t);  // two legs
      std::vector<Option>& o = options[k];
      o.push_back({2.0 * no_leg, -1, -1});
      for (std::size_t i = 0; i < lg.size(); ++i) {
        if (!gated(r, lg[i])) continue;
        const double ci = cost(static_cast<long>(2 * r), static_cast<long>(lg[i]));
        o.push_back({ci + no_leg, static_cast<int>(lg[i]), -1});
        const Eigen::Vector2d la = legs[cols[lg[i]]].position;
        for (std::size_t j = i + 1; j < lg.size(); ++j) {
          if (!gated(r, lg[j])) continue;
          const Eigen::Vector2d lb = legs[cols[lg[j]]].position;
          if ((la - lb).norm() > pairing.max_leg_pair_distance) continue;
          const Eigen::Vector2d m = 0.5 * (la + lb) - t.position(), s = la - lb;
          o.push_back({m.dot(Mi * m) + s.dot(Sepi * s) + log_dets, static_cast<int>(lg[i]), static_cast<int>(lg[j])});
        }
      }
      std::sort(o.begin(), o.end(), [](const Option& x, const Option& y) { return x.cost < y.cost; });
    }
    // rest[k]: the sum of the cheapest options of tracks k.. (a bound that ignores shared legs).
    std::vector<double> rest(tr.size() + 1, 0.0);
    for (std::size_t k = tr.size(); k-- > 0;) rest[k] = rest[k + 1] + options[k].front().cost;
    std::vector<char> used(nc, 0);
    std::vector<std::size_t> pick(tr.size(), 0), best_pick;
    double best = std::numeric_limits<double>::infinity();
    long nodes = 0;
    bool aborted = false;
    std::function<void(std::size_t, double)> search = [&](std::size_t k, double acc) {
      if (aborted || ++nodes > params_.joint_pairs_max_nodes) {
        aborted = true;
        return;
      }
      if (k == tr.size()) {
        if (acc < best) {
          best = acc;
          best_pick = pick;
        }
        return;
      }
      for (std::size_t q = 0; q < options[k].size(); ++q) {
        const Option& o = options[k][q];
        if (acc + o.cost + rest[k + 1] >= best) break;  // sorted: every later option costs more
        if ((o.a >= 0 && used[static_cast<std::size_t>(o.a)]) || (o.b >= 0 && used[static_cast<std::size_t>(o.b)]))
          continue;
        for (int leg : {o.a, o.b})
          if (leg >= 0) used[static_cast<std::size_t>(leg)] = 1;
        pick[k] = q;
        search(k + 1, acc + o.cost);
        for (int leg : {o.a, o.b})
          if (leg >= 0) used[static_cast<std::size_t>(leg)] = 0;
      }
    };
    search(0, 0.0);
    if (aborted || best_pick.empty()) continue;
    for (std::size_t k = 0; k < tr.size(); ++k) {
      const Option& o = options[k][best_pick[k]];
      match[2 * tr[k]] = o.a;
      match[2 * tr[k] + 1] = o.b;
    }
  }
}

// Group-aware split: two people entering side by side often start as one track, and the legs of the second are
// then "gated by a confirmed track" and never start their own. A confirmed track with four or more legs in its
// gate (two taken, two or more that nobody took) for split_scans consecutive scans is re-paired closest-first:
// it keeps the pair nearest its prediction, the other pairs become detections that start tracks.
void PeopleTracker::splitGroups(const std::vector<LegDetection>& legs, const DetectorParams& pairing,
                                const Eigen::MatrixXd& cost, const std::vector<std::size_t>& rows,
                                const std::vector<std::size_t>& cols, std::vector<std::vector<std::size_t>>& track_legs,
                                std::vector<bool>& leg_used, std::vector<PersonDetection>& split) {
  constexpr double kForbidden = 1e9;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    Track& t = tracks_[rows[r]];
    std::vector<std::size_t>& mine = track_legs[rows[r]];
    std::vector<std::size_t> in_gate = mine;
    for (std::size_t c = 0; c < cols.size(); ++c)
      if (cost(static_cast<long>(2 * r), static_cast<long>(c)) < kForbidden && !leg_used[cols[c]])
        in_gate.push_back(cols[c]);
    t.split_evidence = (mine.size() == 2 && in_gate.size() >= 4) ? t.split_evidence + 1 : 0;
    if (t.split_evidence < params_.split_scans) continue;
    // Closest-first pairing of the legs in the gate (as pairLegs, but keeping the leg indices).
    std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
    for (std::size_t a = 0; a < in_gate.size(); ++a)
      for (std::size_t b = a + 1; b < in_gate.size(); ++b) {
        const double d = (legs[in_gate[a]].position - legs[in_gate[b]].position).norm();
        if (d <= pairing.max_leg_pair_distance) candidates.emplace_back(d, in_gate[a], in_gate[b]);
      }
    std::sort(candidates.begin(), candidates.end());
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    std::vector<std::size_t> taken;
    for (const auto& [d, a, b] : candidates) {
      if (std::find(taken.begin(), taken.end(), a) != taken.end() || std::find(taken.begin(), taken.end(), b) != taken.end())
        continue;
      pairs.emplace_back(a, b);
      taken.push_back(a);
      taken.push_back(b);
    }
    if (pairs.size() < 2) continue;
    t.split_evidence = 0;
    // The track keeps the pair nearest its prediction; every other pair starts a track.
    auto mid = [&](const std::pair<std::size_t, std::size_t>& q) {
      return Eigen::Vector2d(0.5 * (legs[q.first].position + legs[q.second].position));
    };
    std::size_t keep = 0;
    for (std::size_t k = 1; k < pairs.size(); ++k)
      if ((mid(pairs[k]) - t.position()).squaredNorm() < (mid(pairs[keep]) - t.position()).squaredNorm()) keep = k;
    for (std::size_t j : in_gate) leg_used[j] = true;  // legs left unpaired are not evidence of anyone else
    mine = {pairs[keep].first, pairs[keep].second};
    for (std::size_t k = 0; k < pairs.size(); ++k)
      if (k != keep) {
        split.push_back(personFromLegs(legs[pairs[k].first], legs[pairs[k].second], pairing));
        split_births_.push_back(split.back().position);
      }
  }
}

void PeopleTracker::predict(double stamp) {
  for (Track& t : tracks_) predictTrack(t, stamp, params_);
}

Eigen::Matrix2d PeopleTracker::legCovariance(const Track& t, const DetectorParams& pairing) const {
  return legSpread(t) + pairing.sigma_pair * pairing.sigma_pair * Eigen::Matrix2d::Identity();
}

double PeopleTracker::legConfidenceCost(const Track& t) const {
  return params_.confidence_cost * (1.0 - t.confidence);
}

Eigen::Matrix2d PeopleTracker::legSpread(const Track& t) const {
  const double along2 = params_.leg_spread_sigma * params_.leg_spread_sigma;
  const Eigen::Vector2d v = t.velocity();
  const double speed = v.norm();
  if (!(speed > params_.leg_spread_min_speed)) return along2 * Eigen::Matrix2d::Identity();
  const Eigen::Vector2d u = v / speed;
  const double lat = std::min(params_.leg_spread_lateral_sigma, params_.leg_spread_sigma);
  const Eigen::Matrix2d uu = u * u.transpose();
  return along2 * uu + lat * lat * (Eigen::Matrix2d::Identity() - uu);
}

// Re-identification of a recently deleted confirmed track (typically lost behind someone for longer than
// delete_timeout): the new track takes the old id if it lies within the gate of the old track's prediction.
void PeopleTracker::reidentify(std::size_t new_track) {
  Track& n = tracks_[new_track];
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_k = deleted_.size();
  // Deleted tracks are predicted with the walking process noise only (the manoeuvre mode's covariance grows so
  // fast over seconds that its gate would take anyone).
  TrackerParams walking = params_;
  walking.maneuver_process_noise = 0.0;
  for (std::size_t k = 0; k < deleted_.size(); ++k) {
    if (last_stamp_ - deleted_[k].deleted > params_.reid_window) continue;
    Track old = deleted_[k].track;
    old.mode_state[0] = old.state;
    old.mode_covariance[0] = old.covariance;
    predictTrack(old, last_stamp_, walking);
    const Eigen::Vector2d nu = n.position() - old.position();
    const Eigen::Matrix2d S = old.positionCovariance() + n.positionCovariance();
    const double d2 = nu.dot(S.ldlt().solve(nu));
    if (d2 > params_.reid_gate_chi2 || nu.norm() > params_.reid_max_distance) continue;
    const double cost = d2 + std::log(S.determinant());
    if (cost < best) best = cost, best_k = k;
  }
  if (best_k == deleted_.size()) return;
  n.id = deleted_[best_k].track.id;
  n.first_stamp = deleted_[best_k].track.first_stamp;
  if (n.leg_separation <= 0.0) n.leg_separation = deleted_[best_k].track.leg_separation;
  deleted_.erase(deleted_.begin() + static_cast<long>(best_k));
}

bool PeopleTracker::onStaticMap(const Eigen::Vector2d& p) const {
  return static_map_ && static_map_->occupiedWithin(p, params_.static_map_margin);
}

void PeopleTracker::applyUpdate(Track& t, const PersonDetection& d) {
  if (!t.confirmed) t.score += scoreIncrement(innovation(t, d), params_);
  if (!immOn(params_)) {
    if (params_.adaptive_nis_threshold > 0.0) {
      const double w = params_.adaptive_nis_smoothing;
      t.nis = (1.0 - w) * t.nis + w * innovation(t, d).d2;  // one mode: state/covariance are mode 0's
    }
    updateMode(t.mode_state[0], t.mode_covariance[0], d);
    combineModes(t, 1);
  } else {
    // Mode probabilities follow the modes' measurement likelihoods (in log space: far detections underflow).
    double ll[2];
    for (int k = 0; k < 2; ++k) ll[k] = updateMode(t.mode_state[k], t.mode_covariance[k], d);
    const double m = std::max(ll[0], ll[1]);
    const Eigen::Vector2d w(t.mode_probability[0] * std::exp(ll[0] - m), t.mode_probability[1] * std::exp(ll[1] - m));
    if (w.sum() > 0.0) t.mode_probability = w / w.sum();
    combineModes(t, 2);
  }
  t.last_update = t.stamp;
  ++t.hits;
  if (d.legs == 2 && d.leg_separation > 0.0)
    t.leg_separation = t.leg_separation > 0.0 ? 0.8 * t.leg_separation + 0.2 * d.leg_separation : d.leg_separation;
}

void PeopleTracker::associateGnn(const std::vector<PersonDetection>& dets, std::vector<bool>& used,
                                 bool confirmed_stage) {
  std::vector<std::size_t> rows, cols;
  for (std::size_t i = 0; i < tracks_.size(); ++i)
    if (tracks_[i].confirmed == confirmed_stage && !updated_[i]) rows.push_back(i);
  for (std::size_t j = 0; j < dets.size(); ++j)
    if (!used[j]) cols.push_back(j);
  if (rows.empty() || cols.empty()) return;
  constexpr double kForbidden = 1e9;
  Eigen::MatrixXd cost(static_cast<long>(rows.size()), static_cast<long>(cols.size()));
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const Innovation in = innovation(tracks_[rows[r]], dets[cols[c]]);
      // Mahalanobis distance plus the log-determinant: the negative log-likelihood up to a constant.
      cost(static_cast<long>(r), static_cast<long>(c)) =
          in.d2 <= params_.gate_chi2 ? in.d2 + std::log(in.S.determinant()) : kForbidden;
    }
  const std::vector<int> match = solveAssignment(cost, kForbidden);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (match[r] < 0) continue;
    const std::size_t j = cols[static_cast<std::size_t>(match[r])];
    applyUpdate(tracks_[rows[r]], dets[j]);
    updated_[rows[r]] = true;
    used[j] = true;
  }
  if (confirmed_stage && params_.maneuver_gate_sigma > 0.0) maneuverGate(dets, used, rows);
}

// TrackerParams::maneuver_gate_sigma: confirmed tracks the gate left without a detection.
void PeopleTracker::maneuverGate(const std::vector<PersonDetection>& dets, std::vector<bool>& used,
                                 const std::vector<std::size_t>& rows) {
  const Eigen::Matrix2d Sm = params_.maneuver_gate_sigma * params_.maneuver_gate_sigma * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d Sv = Sm / (params_.maneuver_gate_time * params_.maneuver_gate_time);
  const auto held_by_another = [&](std::size_t i, std::size_t j) {
    for (std::size_t k = 0; k < tracks_.size(); ++k)
      if (k != i && innovation(tracks_[k], dets[j]).d2 <= params_.gate_chi2) return true;
    return false;
  };
  for (const std::size_t i : rows) {
    if (updated_[i]) continue;
    Track& t = tracks_[i];
    double best = params_.gate_chi2;
    std::size_t pick = dets.size();
    for (std::size_t j = 0; j < dets.size(); ++j) {
      if (used[j] || dets[j].legs == 1) continue;  // a lone leg is too weak a sign that the person turned
      const Innovation in = innovation(t, dets[j]);
      const double d2 = in.nu.dot((in.S + Sm).ldlt().solve(in.nu));
      if (d2 > best || held_by_another(i, j)) continue;
      best = d2;
      pick = j;
    }
    if (pick == dets.size()) continue;
    for (Eigen::Matrix4d& P : t.mode_covariance) {
      P.topLeftCorner<2, 2>() += Sm;
      P.bottomRightCorner<2, 2>() += Sv;
    }
    t.covariance.topLeftCorner<2, 2>() += Sm;
    t.covariance.bottomRightCorner<2, 2>() += Sv;
    applyUpdate(t, dets[pick]);
    if (params_.adaptive_nis_threshold > 0.0) t.nis = std::max(t.nis, 2.0 * params_.adaptive_nis_threshold);
    updated_[i] = true;
    used[pick] = true;
  }
}

// JPDA (Bar-Shalom & Fortmann): joint association events are enumerated per gating cluster; each track is
// updated with the probability-weighted innovation and the spread-of-innovations covariance term.
void PeopleTracker::associateJpda(const std::vector<PersonDetection>& dets, std::vector<bool>& used) {
  const std::size_t nt = tracks_.size(), nd = dets.size();
  if (nt == 0 || nd == 0) return;
  std::vector<std::vector<Innovation>> inn(nt, std::vector<Innovation>(nd));
  std::vector<std::vector<std::size_t>> gated(nt);
  const auto in_gate = [&](std::size_t i, std::size_t j) { return inn[i][j].d2 <= params_.gate_chi2; };
  for (std::size_t i = 0; i < nt; ++i)
    for (std::size_t j = 0; j < nd; ++j) {
      inn[i][j] = innovation(tracks_[i], dets[j]);
      if (in_gate(i, j)) gated[i].push_back(j);
    }
  const double pd = params_.detection_probability;
  std::vector<double> det_mass(nd, 0.0);
  for (const GatingCluster& cluster : gatingClusters(nt, nd, in_gate)) {
    const std::vector<std::size_t>& members = cluster.tracks;
    double events = 1.0;
    for (std::size_t i : members) events *= static_cast<double>(gated[i].size() + 1);
    if (events > params_.jpda_max_events) {
      // Too many joint events: GNN inside this cluster.
      std::vector<bool> keep(nt);
      for (std::size_t i = 0; i < nt; ++i) keep[i] = updated_[i];
      for (std::size_t i = 0; i < nt; ++i) updated_[i] = updated_[i] || std::find(members.begin(), members.end(), i) == members.end();
      associateGnn(dets, used, true);
      associateGnn(dets, used, false);
      for (std::size_t i = 0; i < nt; ++i)
        if (std::find(members.begin(), members.end(), i) == members.end()) updated_[i] = keep[i];
      continue;
    }
    // Likelihood of track i taking detection j relative to clutter: pd * N(nu; 0, S) / clutter density.
    std::vector<std::vector<double>> g(members.size());
    for (std::size_t m = 0; m < members.size(); ++m)
      for (std::size_t j : gated[members[m]]) g[m].push_back(std::exp(scoreIncrement(inn[members[m]][j], params_)));
    std::vector<std::vector<double>> beta(members.size());
    std::vector<double> beta0(members.size(), 0.0);
    for (std::size_t m = 0; m < members.size(); ++m) beta[m].assign(gated[members[m]].size(), 0.0);
    double total = 0.0;
    std::vector<int> choice(members.size(), -1);
    std::vector<char> taken(nd, 0);
    const double miss = 1.0 - pd;
    std::function<void(std::size_t, double)> enumerate = [&](std::size_t m, double w) {
      if (m == members.size()) {
        total += w;
        for (std::size_t k = 0; k < members.size(); ++k) {
          if (choice[k] < 0) beta0[k] += w;
          else beta[k][static_cast<std::size_t>(choice[k])] += w;
        }
        return;
      }
      choice[m] = -1;
      enumerate(m + 1, w * miss);
      for (std::size_t k = 0; k < gated[members[m]].size(); ++k) {
        const std::size_t j = gated[members[m]][k];
        if (taken[j]) continue;
        taken[j] = 1;
        choice[m] = static_cast<int>(k);
        enumerate(m + 1, w * g[m][k]);
        taken[j] = 0;
      }
      choice[m] = -1;
    };
    enumerate(0, 1.0);
    if (total <= 0.0) continue;
    for (std::size_t m = 0; m < members.size(); ++m) {
      Track& t = tracks_[members[m]];
      const double b0 = beta0[m] / total;
      Eigen::Vector2d nu = Eigen::Vector2d::Zero();
      Eigen::Matrix2d spread = Eigen::Matrix2d::Zero();
      double best = -1.0;
      std::size_t best_j = 0;
      for (std::size_t k = 0; k < gated[members[m]].size(); ++k) {
        const std::size_t j = gated[members[m]][k];
        const double b = beta[m][k] / total;
        det_mass[j] += b;
        nu += b * inn[members[m]][j].nu;
        spread += b * inn[members[m]][j].nu * inn[members[m]][j].nu.transpose();
        if (b > best) best = b, best_j = j;
      }
      if (b0 > 0.5) continue;  // most likely missed: keep the prediction (deletion logic sees no update)
      // Combined update. The measurement covariance of the most likely detection stands in for all of them.
      const PersonDetection& d = dets[best_j];
      if (!t.confirmed) t.score += scoreIncrement(inn[members[m]][best_j], params_);  // the most likely detection's
      const Eigen::Matrix2d S = t.covariance.topLeftCorner<2, 2>() + d.covariance;
      const Eigen::Matrix<double, 4, 2> K = t.covariance.leftCols<2>() * S.inverse();
      const Eigen::Matrix4d Pc = t.covariance - K * S * K.transpose();
      t.state += K * nu;
      t.covariance = b0 * t.covariance + (1.0 - b0) * Pc + K * (spread - nu * nu.transpose()) * K.transpose();
      // JPDA updates the mixture; with IMM both modes restart from it (an approximation: IMM-JPDA proper would
      // update every mode with its own innovations). Mode probabilities are kept.
      t.mode_state.fill(t.state);
      t.mode_covariance.fill(t.covariance);
      t.last_update = t.stamp;
      ++t.hits;
      if (d.legs == 2 && d.leg_separation > 0.0)
        t.leg_separation = t.leg_separation > 0.0 ? 0.8 * t.leg_separation + 0.2 * d.leg_separation : d.leg_separation;
      updated_[members[m]] = true;
    }
  }
  for (std::size_t j = 0; j < nd; ++j)
    if (det_mass[j] >= 0.5) used[j] = true;
  if (params_.maneuver_gate_sigma > 0.0) {
    // Confirmed tracks with nothing in their gate (a track whose gated detections were judged clutter keeps that
    // judgement); a detection with any event weight lies in some track's gate, which maneuverGate() skips.
    std::vector<std::size_t> rows;
    for (std::size_t i = 0; i < nt; ++i)
      if (tracks_[i].confirmed && !updated_[i] && gated[i].empty()) rows.push_back(i);
    maneuverGate(dets, used, rows);
  }
  // Detections gated by some track but mostly explained as clutter stay available for initiation only if they
  // are not next to a confirmed track (checked in initiate()).
}

void PeopleTracker::initiate(const std::vector<PersonDetection>& dets, const std::vector<bool>& used) {
  for (std::size_t j = 0; j < dets.size(); ++j) {
    if (used[j]) continue;
    bool near = false;
    for (const Track& t : tracks_)
      near |= t.confirmed && (t.position() - dets[j].position).norm() < params_.min_init_distance;
    for (const Track& t : tracks_)  // also do not start two tracks on one spot in the same scan
      near |= t.first_stamp == last_stamp_ && t.hits == 1 && (t.position() - dets[j].position).norm() < params_.min_init_distance;
    for (const Eigen::Vector2d& b : split_births_) near &= (b - dets[j].position).squaredNorm() > 1e-12;
    if (near) continue;
    Track t;
    t.id = next_id_++;
    t.state << dets[j].position, 0.0, 0.0;
    t.covariance.setZero();
    t.covariance.topLeftCorner<2, 2>() = dets[j].covariance;
    const double v2 = params_.initial_velocity_sigma * params_.initial_velocity_sigma;
    t.covariance(2, 2) = t.covariance(3, 3) = v2;
    t.mode_state.fill(t.state);
    t.mode_covariance.fill(t.covariance);
    // A new track starts at the Markov chain's stationary mode probabilities.
    const double rate_sum = params_.maneuver_rate + params_.maneuver_end_rate;
    const double p1 = immOn(params_) && rate_sum > 0.0 ? params_.maneuver_rate / rate_sum : 0.0;
    t.mode_probability = Eigen::Vector2d(1.0 - p1, p1);
    t.stamp = t.first_stamp = t.last_update = last_stamp_;
    t.hits = 1;
    t.confirmed = params_.confirm_hits <= 1;
    t.confidence = params_.confidence_gain;
    t.leg_separation = dets[j].legs == 2 ? dets[j].leg_separation : 0.0;
    tracks_.push_back(t);
  }
}

void PeopleTracker::prune() {
  std::erase_if(deleted_, [&](const Deleted& d) { return last_stamp_ - d.deleted > params_.reid_window; });
  std::erase_if(tracks_, [&](const Track& t) {
    const double since = last_stamp_ - t.last_update;
    const double max_var = t.positionCovariance().diagonal().maxCoeff();
    // A standing person unseen is as likely to be there still as an occluded one (TrackerParams::standing_*).
    const double timeout = t.occluded_since_update || standing(t, params_)
                               ? std::max(params_.delete_timeout, params_.occluded_delete_timeout)
                               : params_.delete_timeout;
    const bool remove = (!t.confirmed && since > params_.tentative_timeout) ||
                        (t.confirmed && since > timeout) ||
                        t.free_space_scans >= params_.free_space_delete_scans ||
                        max_var > params_.max_position_sigma * params_.max_position_sigma;
    if (remove && t.confirmed && params_.reid_window > 0.0) deleted_.push_back({t, last_stamp_});
    return remove;
  });
}

}  // namespace cairn::people_tracking
