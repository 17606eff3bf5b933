#include "cairn/sim/laser.hpp"

#include "cairn/sim/diff_drive.hpp"  // integrateArc

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace cairn::sim {

bool LaserConfig::fullCircle() const { return fov >= 2.0 * std::numbers::pi - 1e-9; }

int LaserConfig::beams() const {
  const double n = fov / resolution;
  return fullCircle() ? static_cast<int>(std::lround(n)) : static_cast<int>(std::lround(n)) + 1;
}

void LaserConfig::validate() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument("laser." + what); };
  if (!(fov > 0 && fov <= 2.0 * std::numbers::pi + 1e-9)) bad("fov must be in (0, 2 pi]");
  if (!(resolution > 0 && resolution <= fov)) bad("resolution must be in (0, fov]");
  if (!(rate > 0)) bad("rate must be > 0");
  if (!(range_min >= 0 && range_max > range_min)) bad("range_max must exceed range_min >= 0");
  if (!(noise_sigma >= 0)) bad("noise_sigma must be >= 0");
  if (!(outlier_prob >= 0 && outlier_prob <= 1)) bad("outlier_prob must be in [0, 1]");
  if (!(dropout_prob >= 0 && dropout_prob <= 1)) bad("dropout_prob must be in [0, 1]");
}

LaserSimulator::LaserSimulator(LaserConfig config, const SegmentGrid& walls) : config_(std::move(config)), walls_(walls) {
  config_.validate();
  n_ = config_.beams();
  cos_.resize(n_);
  sin_.resize(n_);
  for (int i = 0; i < n_; ++i) {
    const double a = config_.angleMin() + i * config_.resolution;
    cos_[i] = std::cos(a);
    sin_[i] = std::sin(a);
  }
}

// Calls fn(i) for every beam whose angle lies in [a0 - inc, a0 + width + inc] (laser frame, wrapping).
template <class HitFn>
void LaserSimulator::forBeamsInInterval(double a0, double width, HitFn&& fn) const {
  const double inc = config_.resolution;
  const double two_pi = 2.0 * std::numbers::pi;
  double rel = std::fmod(a0 - config_.angleMin(), two_pi);
  if (rel < 0) rel += two_pi;
  const long first = static_cast<long>(std::floor(rel / inc)) - 1;
  const long last = static_cast<long>(std::ceil((rel + width) / inc)) + 1;
  const long per_rev = std::lround(two_pi / inc);
  if (last - first + 1 >= per_rev) {  // covers everything
    for (int i = 0; i < n_; ++i) fn(i);
    return;
  }
  for (long j = first; j <= last; ++j) {
    long i = j % per_rev;
    if (i < 0) i += per_rev;
    if (i < n_) fn(static_cast<int>(i));
  }
}

void LaserSimulator::castIdeal(const Pose2& lp, const std::vector<Segment>& dynamic_segments,
                               const std::vector<Circle>& circles, std::vector<RayHit>& hits) const {
  hits.resize(n_);
  const Vec2 o{lp.x, lp.y};
  const double c = std::cos(lp.theta), s = std::sin(lp.theta);
  const double rmax = config_.range_max;
  for (int i = 0; i < n_; ++i) {
    const Vec2 d{c * cos_[i] - s * sin_[i], s * cos_[i] + c * sin_[i]};
    hits[i] = walls_.cast(o, d, rmax);
  }
  auto beamDir = [&](int i) { return Vec2{c * cos_[i] - s * sin_[i], s * cos_[i] + c * sin_[i]}; };
  // Dynamic geometry: only the beams inside each primitive's angular extent are tested.
  for (const auto& seg : dynamic_segments) {
    const Vec2 ra = seg.a - o, rb = seg.b - o;
    if (std::min(norm(ra), norm(rb)) > rmax && std::abs(cross(rb - ra, ra)) / std::max(1e-12, norm(rb - ra)) > rmax)
      continue;
    const double aa = std::atan2(ra.y, ra.x) - lp.theta, ab = std::atan2(rb.y, rb.x) - lp.theta;
    double span = normalizeAngle(ab - aa);  // signed angle from a to b, |span| <= pi
    const double start = span >= 0 ? aa : aa + span;
    span = std::abs(span);
    forBeamsInInterval(start, span, [&](int i) {
      const double t = raySegment(o, beamDir(i), seg.a, seg.b);
      if (t >= 0.0 && t < hits[i].range) hits[i] = {t, seg.reflectivity, true};
    });
  }
  for (const auto& circ : circles) {
    const Vec2 rc = circ.center - o;
    const double dist = norm(rc);
    if (dist - circ.radius > rmax) continue;
    const double half = dist > circ.radius ? std::asin(circ.radius / dist) : std::numbers::pi;
    const double bearing = std::atan2(rc.y, rc.x) - lp.theta;
    forBeamsInInterval(bearing - half, 2.0 * half, [&](int i) {
      const double t = rayCircle(o, beamDir(i), circ.center, circ.radius);
      if (t >= 0.0 && t < hits[i].range) hits[i] = {t, circ.reflectivity, true};
    });
  }
}

void LaserSimulator::castIdealMoving(const Pose2& robot_pose, Twist2 vel, const std::vector<Segment>& dynamic_segments,
                                     const std::vector<Circle>& circles, std::vector<RayHit>& hits) const {
  hits.resize(n_);
  const double rmax = config_.range_max;
  const double dt = config_.resolution / (2.0 * std::numbers::pi) / config_.rate;  // time between beams
  const double T = dt * (n_ - 1);
  std::vector<Pose2>& origins = origins_;
  origins.resize(n_);
  for (int i = 0; i < n_; ++i) origins[i] = compose(integrateArc(robot_pose, vel, i * dt), config_.mount);
  auto beamDir = [&](int i) {
    const double c = std::cos(origins[i].theta), s = std::sin(origins[i].theta);
    return Vec2{c * cos_[i] - s * sin_[i], s * cos_[i] + c * sin_[i]};
  };
  for (int i = 0; i < n_; ++i) hits[i] = walls_.cast({origins[i].x, origins[i].y}, beamDir(i), rmax);
  // Culling as in castIdeal from the first beam's origin, widened by how far the origin moves and turns
  // during the scan.
  const Pose2& lp = origins.front();
  const Vec2 o{lp.x, lp.y};
  const double shift = std::abs(vel.v) * T + std::abs(vel.w) * T * std::hypot(config_.mount.x, config_.mount.y);
  const double turn = std::abs(vel.w) * T;
  auto margin = [&](double dist) { return turn + (dist > shift ? std::asin(shift / dist) : std::numbers::pi); };
  for (const auto& seg : dynamic_segments) {
    const Vec2 ra = seg.a - o, rb = seg.b - o;
    const double e = norm(rb - ra);
    const double dist = e > 1e-12 ? std::min({norm(ra), norm(rb), std::abs(cross(rb - ra, ra)) / e}) : norm(ra);
    if (std::min(norm(ra), norm(rb)) > rmax + shift && dist > rmax + shift) continue;
    const double aa = std::atan2(ra.y, ra.x) - lp.theta, ab = std::atan2(rb.y, rb.x) - lp.theta;
    double span = normalizeAngle(ab - aa);
    const double start = span >= 0 ? aa : aa + span;
    span = std::abs(span);
    const double m = margin(dist);
    forBeamsInInterval(start - m, span + 2 * m, [&](int i) {
      const double t = raySegment({origins[i].x, origins[i].y}, beamDir(i), seg.a, seg.b);
      if (t >= 0.0 && t < hits[i].range) hits[i] = {t, seg.reflectivity, true};
    });
  }
  for (const auto& circ : circles) {
    const Vec2 rc = circ.center - o;
    const double dist = norm(rc);
    if (dist - circ.radius > rmax + shift) continue;
    const double half = dist > circ.radius ? std::asin(circ.radius / dist) : std::numbers::pi;
    const double m = margin(std::max(0.0, dist - circ.radius));
    const double bearing = std::atan2(rc.y, rc.x) - lp.theta;
    forBeamsInInterval(bearing - half - m, 2.0 * (half + m), [&](int i) {
      const double t = rayCircle({origins[i].x, origins[i].y}, beamDir(i), circ.center, circ.radius);
      if (t >= 0.0 && t < hits[i].range) hits[i] = {t, circ.reflectivity, true};
    });
  }
}

LaserScan LaserSimulator::scan(const Pose2& robot_pose, double stamp, const std::vector<Segment>& dynamic_segments,
                               const std::vector<Circle>& circles, Rng& rng) const {
  LaserScan out;
  scan(robot_pose, stamp, dynamic_segments, circles, rng, out);
  return out;
}

void LaserSimulator::scan(const Pose2& robot_pose, double stamp, const std::vector<Segment>& dynamic_segments,
                          const std::vector<Circle>& circles, Rng& rng, LaserScan& out, Twist2 velocity) const {
  const LaserConfig& cfg = config_;
  if (cfg.motion_distortion && (velocity.v != 0.0 || velocity.w != 0.0))
    castIdealMoving(robot_pose, velocity, dynamic_segments, circles, hits_);
  else
    castIdeal(compose(robot_pose, cfg.mount), dynamic_segments, circles, hits_);
  out.stamp = stamp;
  out.frame_id = cfg.frame_id;
  out.angle_min = static_cast<float>(cfg.angleMin());
  out.angle_increment = static_cast<float>(cfg.resolution);
  out.angle_max = static_cast<float>(cfg.angleMin() + (n_ - 1) * cfg.resolution);
  out.scan_time = static_cast<float>(1.0 / cfg.rate);
  // A rotating scanner sweeps a full revolution per scan period.
  out.time_increment = static_cast<float>(cfg.resolution / (2.0 * std::numbers::pi) / cfg.rate);
  out.range_min = static_cast<float>(cfg.range_min);
  out.range_max = static_cast<float>(cfg.range_max);
  out.ranges.resize(n_);
  out.intensities.resize(n_);
  constexpr float inf = std::numeric_limits<float>::infinity();
  for (int i = 0; i < n_; ++i) {
    const RayHit& h = hits_[i];
    // Every beam draws the same number of random numbers, so one beam's outcome never shifts the
    // stream of the others (determinism under config changes of single beams).
    const double g = rng.gaussian();
    const double u_out = rng.uniform();
    const double u_len = rng.uniform();
    const double u_drop = rng.uniform();
    if (!h.hit || u_drop < cfg.dropout_prob) {
      out.ranges[i] = inf;
      out.intensities[i] = 0.0F;
      continue;
    }
    double r = h.range;
    if (u_out < cfg.outlier_prob) r = cfg.range_min + u_len * (r - cfg.range_min);
    else r += cfg.noise_sigma * g;
    if (r < cfg.range_min) r = cfg.range_min;
    if (r > cfg.range_max) {
      out.ranges[i] = inf;
      out.intensities[i] = 0.0F;
      continue;
    }
    out.ranges[i] = static_cast<float>(r);
    out.intensities[i] = cfg.binary_intensity ? (h.reflectivity >= cfg.binary_threshold ? 1.0F : 0.0F)
                                              : static_cast<float>(cfg.intensity_scale * h.reflectivity);
  }
}

}  // namespace cairn::sim
