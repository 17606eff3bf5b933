#include "cairn/sim/simulator.hpp"

#include <cmath>
#include <algorithm>
#include <cstring>

namespace cairn::sim {

namespace {
// Independent random streams per subsystem (see Rng::fork).
enum Stream : std::uint64_t { kLaser = 1, kOdometry = 2, kPeople = 3 };
}  // namespace

Simulator::Simulator(World world, SimConfig config)
    : world_(std::move(world)),
      config_(std::move(config)),
      grid_(world_.walls),
      laser_(config_.laser, grid_),
      robot_(config_.robot, config_.start.value_or(world_.robot_start)),
      odom_(config_.odometry, robot_.pose(), Rng(config_.seed).fork(kOdometry)),
      people_(world_, config_.gait, Rng(config_.seed).fork(kPeople), config_.people, config_.crowd),
      laser_rng_(Rng(config_.seed).fork(kLaser)) {
  people_.setSocialForce(config_.social);
  people_.setRobot({robot_.pose().x, robot_.pose().y}, config_.robot.footprint_radius);
  people_.update(0.0);
}

void Simulator::setCommand(Twist2 cmd) {
  cmd_ = cmd;
  robot_.setCommand(cmd, t_);
}

void Simulator::followRoute(std::vector<Vec2> waypoints, RouteConfig config) { route_.emplace(std::move(waypoints), config); }

void Simulator::cancelRoute() { route_.reset(); }

Odometry Simulator::odometry() const {
  Odometry o;
  o.stamp = t_;
  o.pose = odom_.pose();
  o.twist = robot_.velocity();
  return o;
}

void Simulator::dynamicGeometry(std::vector<Segment>& segments, std::vector<Circle>& circles) const {
  world_.dynamicGeometry(t_, segments, circles);
  people_.legCircles(circles);
}

double Simulator::clearance(Vec2 p, double max_dist) const {
  // static walls from the grid; doors and furniture at the current time (people do not block the robot)
  double best = grid_.distanceToNearest(p, max_dist);
  auto segDist = [](Vec2 q, Vec2 a, Vec2 b) {
    const Vec2 e = b - a;
    const double l2 = dot(e, e);
    const double u = l2 > 0 ? std::clamp(dot(q - a, e) / l2, 0.0, 1.0) : 0.0;
    return norm(q - (a + u * e));
  };
  for (const auto& d : world_.doors) {
    const Segment s = d.panel(t_);
    best = std::min(best, segDist(p, s.a, s.b));
  }
  collision_segments_.clear();
  collision_circles_.clear();
  for (const auto& f : world_.furniture) {
    const Pose2 fp = f.poseAt(t_);
    if (norm(Vec2{fp.x, fp.y} - p) > max_dist + 0.5 * std::hypot(f.length, f.width)) continue;
    f.geometry(t_, collision_segments_, collision_circles_);
  }
  for (const auto& s : collision_segments_) best = std::min(best, segDist(p, s.a, s.b));
  for (const auto& c : collision_circles_) best = std::min(best, std::max(0.0, norm(p - c.center) - c.radius));
  return best;
}

void Simulator::stepOnce(SimOutput& out) {
  // Outputs that fall due at the current time come first, so the first scan and odometry are at t = 0.
  const double dt = config_.physics_dt;
  if (step_ >= next_odom_step_) {
    Odometry o = odometry();
    out.odometry.push_back(o);
    o.frame_id = "map";
    o.pose = robot_.pose();
    out.ground_truth.push_back(o);
    ++odom_count_;
    next_odom_step_ = std::lround(odom_count_ / (config_.odom_rate * dt));
  }
  if (step_ >= next_scan_step_) {
    dyn_segments_.clear();
    dyn_circles_.clear();
    dynamicGeometry(dyn_segments_, dyn_circles_);
    out.scans.emplace_back();
    laser_.scan(robot_.pose(), t_, dyn_segments_, dyn_circles_, laser_rng_, out.scans.back(), robot_.velocity());
    ++scan_count_;
    next_scan_step_ = std::lround(scan_count_ / (config_.laser.rate * dt));
  }
  if (route_ && !route_->done()) robot_.setCommand(route_->command(robot_.pose(), t_), t_);
  robot_.step(dt, t_, [this](Vec2 p, double max_dist) { return clearance(p, max_dist); });
  odom_.update(robot_.pose());
  ++step_;
  t_ = step_ * dt;  // no accumulated floating-point drift
  people_.setRobot({robot_.pose().x, robot_.pose().y}, config_.robot.footprint_radius);
  people_.update(t_);
}

void Simulator::advance(double duration, SimOutput& out) {
  const long end = std::lround((t_ + duration) / config_.physics_dt);
  while (step_ < end) stepOnce(out);
}

std::uint64_t scanDigest(const LaserScan& s, std::uint64_t h) {
  auto mix = [&](const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 0x100000001b3ULL;
    }
  };
  mix(&s.stamp, sizeof s.stamp);
  mix(&s.angle_min, sizeof(float));
  mix(&s.angle_increment, sizeof(float));
  mix(&s.range_max, sizeof(float));
  mix(s.ranges.data(), s.ranges.size() * sizeof(float));
  mix(s.intensities.data(), s.intensities.size() * sizeof(float));
  return h;
}

}  // namespace cairn::sim
