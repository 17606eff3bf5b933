#include "cairn/people_tracking/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

namespace cairn::people_tracking {

const char* toString(ObjectClass c) {
  switch (c) {
    case ObjectClass::kPersonLeg: return "person_leg";
    case ObjectClass::kTableLeg: return "table_leg";
    case ObjectClass::kChairLeg: return "chair_leg";
    case ObjectClass::kPole: return "pole";
    case ObjectClass::kWall: return "wall";
    case ObjectClass::kDoor: return "door";
    case ObjectClass::kClutter: return "clutter";
  }
  return "?";
}

int Scene::addObject(ObjectClass c, int person) {
  object_class.push_back(c);
  object_person.push_back(person);
  return static_cast<int>(object_class.size()) - 1;
}

void Scene::addCircle(const Eigen::Vector2d& center, double radius, ObjectClass c, int person) {
  circles.push_back({center, radius, addObject(c, person)});
}

void Scene::addSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, ObjectClass c) {
  segments.push_back({a, b, addObject(c)});
}

void Scene::addBox(const Eigen::Vector2d& center, double half_x, double half_y, double yaw, ObjectClass c) {
  const int obj = addObject(c);
  const Eigen::Matrix2d R = Pose2{0, 0, yaw}.rotation();
  const std::array<Eigen::Vector2d, 4> corners{center + R * Eigen::Vector2d(half_x, half_y),
                                               center + R * Eigen::Vector2d(-half_x, half_y),
                                               center + R * Eigen::Vector2d(-half_x, -half_y),
                                               center + R * Eigen::Vector2d(half_x, -half_y)};
  for (std::size_t i = 0; i < 4; ++i) segments.push_back({corners[i], corners[(i + 1) % 4], obj});
}

std::array<Eigen::Vector2d, 2> legCenters(const WalkerState& w) {
  const Eigen::Vector2d fwd(std::cos(w.heading), std::sin(w.heading));
  const Eigen::Vector2d left(-fwd.y(), fwd.x());
  const double swing = w.stride_amplitude * std::sin(w.gait_phase);
  return {w.position + left * w.hip_half_width + fwd * swing, w.position - left * w.hip_half_width - fwd * swing};
}

void addWalker(Scene& scene, const WalkerState& w, int person_id) {
  for (const auto& c : legCenters(w)) scene.addCircle(c, w.leg_radius, ObjectClass::kPersonLeg, person_id);
}

void advanceGait(WalkerState& w, double distance, double dt) {
  constexpr double kStride = 1.3;  // m per full gait cycle (two steps)
  w.gait_phase = std::fmod(w.gait_phase + 2.0 * M_PI * distance / kStride, 2.0 * M_PI);
  const double speed = dt > 0 ? distance / dt : 0.0;
  const double target = std::min(0.3, 0.3 * speed);
  w.stride_amplitude += 0.5 * (target - w.stride_amplitude);  // smooth start/stop
}

namespace {

double wrapAngle(double a) {
  while (a > M_PI) a -= 2.0 * M_PI;
  while (a < -M_PI) a += 2.0 * M_PI;
  return a;
}

// Distance along unit ray d from o to the circle, or +inf.
double rayCircle(const Eigen::Vector2d& o, const Eigen::Vector2d& d, const SceneCircle& c) {
  const Eigen::Vector2d m = o - c.center;
  const double b = m.dot(d);
  const double cc = m.squaredNorm() - c.radius * c.radius;
  const double disc = b * b - cc;
  if (disc < 0.0) return INFINITY;
  const double s = std::sqrt(disc);
  double t = -b - s;
  if (t < 0.0) t = -b + s;
  return t >= 0.0 ? t : INFINITY;
}

double raySegment(const Eigen::Vector2d& o, const Eigen::Vector2d& d, const SceneSegment& s) {
  const Eigen::Vector2d e = s.b - s.a;
  const double denom = d.x() * e.y() - d.y() * e.x();
  if (std::abs(denom) < 1e-12) return INFINITY;
  const Eigen::Vector2d w = s.a - o;
  const double t = (w.x() * e.y() - w.y() * e.x()) / denom;
  const double u = (w.x() * d.y() - w.y() * d.x()) / denom;
  return (t >= 0.0 && u >= 0.0 && u <= 1.0) ? t : INFINITY;
}

}  // namespace

SimScan renderScan(const Scene& scene, const Pose2& sensor, const LaserModel& laser, double stamp,
                   std::mt19937_64& rng) {
  SimScan out;
  out.scan.stamp = stamp;
  out.scan.angle_min = laser.angle_min;
  out.scan.angle_increment = laser.angle_increment;
  out.scan.range_min = laser.range_min;
  out.scan.range_max = laser.range_max;
  const std::size_t n = laser.beams;
  std::vector<double> best(n, INFINITY);
  out.hit_object.assign(n, -1);
  const Eigen::Vector2d o(sensor.x, sensor.y);
  auto dir = [&](std::size_t i) {
    const double a = sensor.theta + laser.angle_min + static_cast<double>(i) * laser.angle_increment;
    return Eigen::Vector2d(std::cos(a), std::sin(a));
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d d = dir(i);
    for (const auto& s : scene.segments) {
      const double t = raySegment(o, d, s);
      if (t < best[i]) {
        best[i] = t;
        out.hit_object[i] = s.object;
      }
    }
  }
  // Circles only touch the beams inside their angular extent.
  for (const auto& c : scene.circles) {
    const Eigen::Vector2d rel = c.center - o;
    const double dist = rel.norm();
    if (dist - c.radius > laser.range_max) continue;
    double half = dist > c.radius ? std::asin(c.radius / dist) : M_PI;
    const double bearing = wrapAngle(std::atan2(rel.y(), rel.x()) - sensor.theta);
    const double lo = (bearing - half - laser.angle_min) / laser.angle_increment;
    const double hi = (bearing + half - laser.angle_min) / laser.angle_increment;
    const long first = std::max(0L, static_cast<long>(std::ceil(std::min(lo, hi))));
    const long last = std::min(static_cast<long>(n) - 1, static_cast<long>(std::floor(std::max(lo, hi))));
    for (long i = first; i <= last; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const double t = rayCircle(o, dir(k), c);
      if (t < best[k]) {
        best[k] = t;
        out.hit_object[k] = c.object;
      }
    }
  }
  std::normal_distribution<double> noise(0.0, laser.noise_sigma);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  out.scan.ranges.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Draw both numbers for every beam so that the random stream does not depend on the scene.
    const double e = noise(rng);
    const double u = uni(rng);
    if (!std::isfinite(best[i]) || best[i] > laser.range_max || u < laser.dropout_prob) {
      out.scan.ranges[i] = std::numeric_limits<float>::infinity();
      out.hit_object[i] = -1;
      continue;
    }
    out.scan.ranges[i] = static_cast<float>(std::max(laser.range_min, best[i] + e));
  }
  return out;
}

ClusterLabel labelCluster(const Cluster& cluster, const SimScan& sim, const Scene& scene) {
  std::map<int, int> votes;
  for (std::size_t b : cluster.beams) ++votes[sim.hit_object[b]];
  int best = -1, count = -1;
  for (const auto& [obj, c] : votes)
    if (c > count) best = obj, count = c;
  ClusterLabel label;
  if (best < 0) return label;
  label.object_class = scene.object_class[static_cast<std::size_t>(best)];
  label.is_person = label.object_class == ObjectClass::kPersonLeg;
  label.person = label.is_person ? scene.object_person[static_cast<std::size_t>(best)] : -1;
  return label;
}

Scene randomTrainingScene(std::mt19937_64& rng, const TrainingSceneParams& params) {
  Scene scene;
  std::uniform_real_distribution<double> U(0.0, 1.0);
  auto uni = [&](double a, double b) { return a + (b - a) * U(rng); };
  auto count = [&](int max) { return std::uniform_int_distribution<int>(0, max)(rng); };
  // Random point in the field of view with range in [rmin, rmax].
  auto place = [&](double rmin, double rmax) {
    const double r = uni(rmin, rmax);
    const double a = uni(-2.3, 2.3);
    return Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
  };

  // Room walls (axis-aligned after a random yaw) with door openings and door leaves.
  const double yaw = uni(-0.4, 0.4);
  const double hx1 = uni(2.0, params.max_distance), hx0 = uni(1.5, params.max_distance);
  const double hy1 = uni(1.5, params.max_distance), hy0 = uni(1.5, params.max_distance);
  const Eigen::Matrix2d R = Pose2{0, 0, yaw}.rotation();
  const std::array<Eigen::Vector2d, 4> corner{R * Eigen::Vector2d(hx1, hy1), R * Eigen::Vector2d(-hx0, hy1),
                                              R * Eigen::Vector2d(-hx0, -hy0), R * Eigen::Vector2d(hx1, -hy0)};
  for (std::size_t w = 0; w < 4; ++w) {
    const Eigen::Vector2d a = corner[w], b = corner[(w + 1) % 4];
    const double len = (b - a).norm();
    if (U(rng) < 0.6 && len > 2.0) {
      const double door_w = uni(0.8, 1.0);
      const double s0 = uni(0.3, len - door_w - 0.3);
      const Eigen::Vector2d u = (b - a) / len;
      const Eigen::Vector2d d0 = a + u * s0, d1 = a + u * (s0 + door_w);
      scene.addSegment(a, d0, ObjectClass::kWall);
      scene.addSegment(d1, b, ObjectClass::kWall);
      // Door leaf opened inwards by a random angle (thin box).
      const double open = uni(0.2, 1.5);
      const Eigen::Vector2d inward = -(a + b) / 2.0;
      const double base = std::atan2(u.y(), u.x());
      const double sgn = (Eigen::Vector2d(-u.y(), u.x()).dot(inward) > 0) ? 1.0 : -1.0;
      const double ang = base + sgn * open;
      const Eigen::Vector2d leaf(std::cos(ang), std::sin(ang));
      scene.addBox(d0 + leaf * door_w / 2.0, door_w / 2.0, 0.02, ang, ObjectClass::kDoor);
    } else {
      scene.addSegment(a, b, ObjectClass::kWall);
    }
  }
  for (int i = count(params.max_tables); i > 0; --i) {
    const Eigen::Vector2d c = place(1.0, params.max_distance - 1.0);
    const double th = uni(0, M_PI), hx = uni(0.3, 0.9), hy = uni(0.3, 0.5), r = uni(0.02, 0.04);
    const Eigen::Matrix2d Rt = Pose2{0, 0, th}.rotation();
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0}) scene.addCircle(c + Rt * Eigen::Vector2d(sx * hx, sy * hy), r, ObjectClass::kTableLeg);
  }
  for (int i = count(params.max_chairs); i > 0; --i) {
    const Eigen::Vector2d c = place(0.8, params.max_distance - 0.5);
    const double th = uni(0, M_PI), h = uni(0.18, 0.24), r = uni(0.012, 0.03);
    const Eigen::Matrix2d Rt = Pose2{0, 0, th}.rotation();
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0}) scene.addCircle(c + Rt * Eigen::Vector2d(sx * h, sy * h), r, ObjectClass::kChairLeg);
  }
  for (int i = count(params.max_poles); i > 0; --i)
    scene.addCircle(place(0.8, params.max_distance), uni(0.1, 0.3), ObjectClass::kPole);
  for (int i = count(params.max_clutter); i > 0; --i)
    scene.addBox(place(0.8, params.max_distance), uni(0.05, 0.5), uni(0.05, 0.4), uni(0, M_PI), ObjectClass::kClutter);
  auto body = [&](WalkerState& w) {
    w.gait_phase = uni(0, 2 * M_PI);
    w.stride_amplitude = U(rng) < 0.3 ? uni(0.0, 0.05) : uni(0.1, 0.3);
    w.hip_half_width = uni(0.07, 0.13);
    w.leg_radius = uni(0.05, 0.08);
  };
  int pid = 0;
  for (int i = count(params.max_people); i > 0; --i) {
    WalkerState w;
    w.position = place(0.6, params.max_distance);
    w.heading = uni(-M_PI, M_PI);
    body(w);
    addWalker(scene, w, pid++);
    if (params.group_probability > 0.0 && U(rng) < params.group_probability) {  // a companion beside w
      WalkerState c = w;
      const double side = U(rng) < 0.5 ? -1.0 : 1.0;
      c.position += side * uni(0.45, 0.8) * Eigen::Vector2d(-std::sin(w.heading), std::cos(w.heading));
      body(c);
      addWalker(scene, c, pid++);
    }
  }
  return scene;
}

}  // namespace cairn::people_tracking
