#include "cairn/people_tracking/detector.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace cairn::people_tracking {

PersonDetector::PersonDetector(std::shared_ptr<const LegClassifier> classifier, DetectorParams params)
    : classifier_(std::move(classifier)), params_(params) {
  if (!classifier_) throw InputError("PersonDetector needs a classifier");
}

std::vector<PersonDetection> PersonDetector::detect(const LaserScan& scan, std::vector<LegDetection>* legs_out) const {
  std::vector<LegDetection> legs = detectLegs(scan);
  if (legs_out) *legs_out = legs;
  return pairLegs(legs, params_);
}

std::vector<LegDetection> PersonDetector::detectLegs(const LaserScan& scan, const MotionEvidence* motion,
                                                    const Pose2& sensor_pose, bool static_map) const {
  std::vector<LegDetection> legs;
  const double track = static_map ? params_.track_leg_confidence_with_map : params_.track_leg_confidence;
  const double plain = std::min(params_.min_leg_confidence, track);
  const bool use_motion = motion != nullptr && motion->size() > 0;
  const bool use_memory = motion != nullptr && motion->remembersFreeSpace();
  double floor = use_motion ? std::min({plain, params_.moving_track_leg_confidence, params_.moving_min_leg_confidence})
                            : plain;
  if (use_memory) floor = std::min(floor, params_.crossed_track_leg_confidence);
  // Moving clusters may also form persons below min_leg_confidence (and single persons below
  // single_leg_min_confidence): then clusters scored in between are checked too.
  const bool moving_births = params_.moving_min_leg_confidence < params_.min_leg_confidence;
  const double births_below = std::max(params_.min_leg_confidence, params_.single_leg_min_confidence);
  std::vector<Eigen::Vector2d> in_frame;
  const Eigen::Matrix2d R = sensor_pose.rotation();  // sensor -> tracking frame, once per scan
  const Eigen::Vector2d t(sensor_pose.x, sensor_pose.y);
  // The leg's centre lies behind its visible surface along the beam.
  auto legCenter = [&](const Eigen::Vector2d& surface) -> Eigen::Vector2d {
    const double r = surface.norm();
    return r > 1e-6 ? Eigen::Vector2d(surface * (1.0 + params_.leg_center_offset / r)) : surface;
  };
  for (const Cluster& c : segmentScan(scan, params_.segmentation)) {
    const Eigen::Vector2d centroid = c.centroid();
    const double range = centroid.norm();
    if (range > params_.max_range) continue;
    if (c.points.size() < SegmentationParams{}.min_points && range < params_.small_cluster_min_range) continue;
    const double width = (c.points.front() - c.points.back()).norm();
    if (width > params_.max_leg_width) continue;
    const double conf = classifier_->score(computeFeatures(c));
    if (conf < floor) continue;
    double moving = 0.0;
    if (conf < plain || (conf < births_below && moving_births)) {
      // Below a plain threshold: is it a leg that moved (motion_evidence.hpp)?
      if (use_motion) {
        in_frame.clear();
        for (const Eigen::Vector2d& p : c.points) in_frame.push_back(R * p + t);
        moving = motion->freeFraction(in_frame, scan.stamp, params_.moving_fraction);
      }
      const bool is_moving = use_motion && moving >= params_.moving_fraction;
      // Not moving, but where the beams went through earlier: not the static background (crossedBefore). Asked at
      // the surface the beams see: the point behind a wall's end may lie in the free space beyond it.
      if (conf < plain && !(is_moving && conf >= params_.moving_track_leg_confidence) &&
          !(use_memory && conf >= params_.crossed_track_leg_confidence &&
            motion->crossedBefore(R * centroid + t, scan.stamp)))
        continue;
    }
    const std::size_t split = width >= params_.split_min_width
                                  ? gapSplitIndex(c, scan.angle_increment, params_.split_gap_ratio,
                                                  params_.split_min_gap_beams)
                                  : 0;
    if (split == 0) {
      legs.push_back({legCenter(centroid), conf, width, moving});
      continue;
    }
    // Two legs in one cluster: each part is a leg with the cluster's score and motion.
    for (const auto& [begin, end] : {std::pair<std::size_t, std::size_t>{0, split}, {split, c.points.size()}})
      legs.push_back({legCenter(c.centroid(begin, end)), conf, (c.points[begin] - c.points[end - 1]).norm(), moving});
  }
  return legs;
}

bool isMovingPersonLeg(const LegDetection& leg, const DetectorParams& params) {
  return leg.moving >= params.moving_fraction && leg.confidence >= params.moving_min_leg_confidence;
}

bool isPersonLeg(const LegDetection& leg, const DetectorParams& params) {
  return leg.confidence >= params.min_leg_confidence || isMovingPersonLeg(leg, params);
}

PersonDetection personFromLegs(const LegDetection& a, const LegDetection& b, const DetectorParams& params) {
  const double d = (a.position - b.position).norm();
  PersonDetection p;
  p.position = 0.5 * (a.position + b.position);
  // The body centre lies between the legs; the along-pair direction is less certain by the half separation
  // (uniform over the spacing: variance (d/2)^2 / 3).
  const Eigen::Vector2d u = (b.position - a.position) / std::max(d, 1e-9);
  const double s2 = params.sigma_pair * params.sigma_pair;
  p.covariance = s2 * Eigen::Matrix2d::Identity() + (d * d / 12.0) * u * u.transpose();
  p.confidence = 0.5 * (a.confidence + b.confidence);
  p.leg_separation = d;
  p.legs = 2;
  return p;
}

PersonDetection personFromLeg(const LegDetection& leg, const DetectorParams& params) {
  PersonDetection p;
  p.position = leg.position;
  p.covariance = params.sigma_single * params.sigma_single * Eigen::Matrix2d::Identity();
  p.confidence = leg.confidence;
  p.legs = 1;
  return p;
}

std::vector<PersonDetection> pairLegs(const std::vector<LegDetection>& legs, const DetectorParams& params) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  std::vector<bool> used(legs.size(), false);
  for (std::size_t i = 0; i < legs.size(); ++i) used[i] = !isPersonLeg(legs[i], params);
  for (std::size_t i = 0; i < legs.size(); ++i)
    for (std::size_t j = i + 1; j < legs.size(); ++j) {
      if (used[i] || used[j]) continue;
      const double d = (legs[i].position - legs[j].position).norm();
      if (d <= params.max_leg_pair_distance) pairs.emplace_back(d, i, j);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<PersonDetection> out;
  for (const auto& pair : pairs) {
    const std::size_t i = std::get<1>(pair), j = std::get<2>(pair);
    if (used[i] || used[j]) continue;
    used[i] = used[j] = true;
    out.push_back(personFromLegs(legs[i], legs[j], params));
  }
  for (std::size_t i = 0; i < legs.size(); ++i)
    if (!used[i] && (legs[i].confidence >= params.single_leg_min_confidence || isMovingPersonLeg(legs[i], params)))
      out.push_back(personFromLeg(legs[i], params));
  return out;
}

std::vector<PersonDetection> transformDetections(std::vector<PersonDetection> detections, const Pose2& pose) {
  const Eigen::Matrix2d R = pose.rotation();
  for (auto& d : detections) {
    d.position = pose.transform(d.position);
    d.covariance = R * d.covariance * R.transpose();
  }
  return detections;
}

}  // namespace cairn::people_tracking
