#include "cairn/sim/diff_drive.hpp"

#include <algorithm>
#include <cmath>

namespace cairn::sim {

Pose2 integrateArc(const Pose2& p, Twist2 vel, double dt) {
  const double dth = vel.w * dt;
  double dx, dy;
  if (std::abs(dth) < 1e-9) {
    dx = vel.v * dt * std::cos(p.theta + 0.5 * dth);
    dy = vel.v * dt * std::sin(p.theta + 0.5 * dth);
  } else {
    const double r = vel.v / vel.w;
    dx = r * (std::sin(p.theta + dth) - std::sin(p.theta));
    dy = -r * (std::cos(p.theta + dth) - std::cos(p.theta));
  }
  return {p.x + dx, p.y + dy, normalizeAngle(p.theta + dth)};
}

DiffDrive::DiffDrive(DiffDriveConfig config, Pose2 start) : config_(config), pose_(start) {}

void DiffDrive::reset(Pose2 pose) {
  pose_ = pose;
  vel_ = cmd_ = {};
  stalled_ = false;
}

void DiffDrive::setCommand(Twist2 cmd, double stamp) {
  cmd_.v = std::clamp(cmd.v, -config_.max_v_reverse, config_.max_v);
  cmd_.w = std::clamp(cmd.w, -config_.max_w, config_.max_w);
  cmd_stamp_ = stamp;
}

namespace {
double approach(double current, double target, double up, double down, double dt) {
  // speeding up (|v| grows in the same direction) is limited by `up`, everything else by `down`
  const bool accelerating = std::abs(target) > std::abs(current) && current * target >= 0.0;
  const double limit = (accelerating ? up : down) * dt;
  return current + std::clamp(target - current, -limit, limit);
}
}  // namespace

void DiffDrive::step(double dt, double now, const SegmentGrid* walls) {
  if (!walls) {
    step(dt, now, ClearanceFn{});
    return;
  }
  step(dt, now, [walls](Vec2 p, double max_dist) { return walls->distanceToNearest(p, max_dist); });
}

void DiffDrive::step(double dt, double now, const ClearanceFn& clearance) {
  Twist2 target = cmd_;
  if (now - cmd_stamp_ > config_.cmd_timeout) target = {};
  vel_.v = approach(vel_.v, target.v, config_.max_acc, config_.max_dec, dt);
  vel_.w = approach(vel_.w, target.w, config_.max_alpha, config_.max_alpha, dt);
  const Pose2 next = integrateArc(pose_, vel_, dt);
  stalled_ = false;
  if (clearance && config_.stall_on_collision) {
    const double r = config_.footprint_radius;
    const double next_clear = clearance({next.x, next.y}, r);
    // allow moves that increase the clearance (so a robot touching an obstacle can back off)
    if (next_clear < r && next_clear <= clearance({pose_.x, pose_.y}, r)) {
      stalled_ = true;
      ++stall_count_;
      vel_ = {};
      return;
    }
  }
  pose_ = next;
}

std::pair<double, double> DiffDrive::wheelSpeeds() const {
  const double half = 0.5 * config_.wheel_separation;
  return {(vel_.v - half * vel_.w) / config_.wheel_radius, (vel_.v + half * vel_.w) / config_.wheel_radius};
}

OdometryModel::OdometryModel(OdometryNoiseConfig config, Pose2 true_start, Rng rng)
    : config_(config), last_true_(true_start), odom_(true_start), rng_(rng) {}

void OdometryModel::update(const Pose2& true_pose) {
  const Pose2 rel = between(last_true_, true_pose);
  last_true_ = true_pose;
  const double dth = rel.theta;
  // signed travelled distance along the chord (backwards motion is negative)
  double d = std::hypot(rel.x, rel.y);
  if (rel.x < 0) d = -d;
  const double ad = std::abs(d), ath = std::abs(dth);
  const OdometryNoiseConfig& c = config_;
  const double d_o = d * (1.0 + c.scale_error) + c.sigma_trans * std::sqrt(ad) * rng_.gaussian();
  const double th_o = dth * (1.0 + c.rotation_scale_error) + c.heading_drift * d +
                      std::sqrt(c.sigma_rot * c.sigma_rot * ath + c.sigma_rot_per_m * c.sigma_rot_per_m * ad) *
                          rng_.gaussian();
  // the chord of an arc points along the mean heading
  odom_ = compose(odom_, {d_o * std::cos(0.5 * th_o), d_o * std::sin(0.5 * th_o), th_o});
}

}  // namespace cairn::sim
