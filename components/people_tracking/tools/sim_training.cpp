// Labelled leg / non-leg clusters from components/sim scans (see sim_training.hpp).
#include "sim_training.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>

#include "cairn/people_tracking/features.hpp"
#include "cairn/sim/people.hpp"
#include "cairn/sim/rng.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::people_tracking {

void addWorldGeometry(const sim::World& world, double t, Scene& scene) {
  auto v = [](const sim::Vec2& p) { return Eigen::Vector2d(p.x, p.y); };
  for (const sim::Segment& w : world.walls) scene.addSegment(v(w.a), v(w.b), ObjectClass::kWall);
  std::vector<sim::Segment> segments;
  std::vector<sim::Circle> circles;
  world.dynamicGeometry(t, segments, circles);
  for (const sim::Segment& w : segments) scene.addSegment(v(w.a), v(w.b), ObjectClass::kWall);
  for (const sim::Circle& c : circles) scene.addCircle(v(c.center), c.radius, ObjectClass::kTableLeg);
}

LaserScan fromSimScan(const sim::LaserScan& scan) {
  LaserScan ls;
  ls.stamp = scan.stamp;
  ls.angle_min = scan.angle_min;
  ls.angle_increment = scan.angle_increment;
  ls.range_min = scan.range_min;
  ls.range_max = scan.range_max;
  ls.ranges = scan.ranges;
  return ls;
}

namespace {

double segmentDistance(const Eigen::Vector2d& p, const sim::Vec2& a, const sim::Vec2& b) {
  const Eigen::Vector2d A(a.x, a.y), B(b.x, b.y), d = B - A;
  const double l2 = d.squaredNorm();
  const double s = l2 > 0 ? std::clamp((p - A).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (A + s * d - p).norm();
}

double circleDistance(const Eigen::Vector2d& p, const sim::Vec2& c, double r) {
  return std::abs((p - Eigen::Vector2d(c.x, c.y)).norm() - r);
}

// Furniture leg class by name (the shipped worlds and the generator below call chairs "chair_*"), else by size:
// chair legs are thinner than 2 cm in the shipped worlds.
ObjectClass furnitureLegClass(const sim::Furniture& f) {
  return (f.name.find("chair") != std::string::npos || f.leg_radius < 0.02) ? ObjectClass::kChairLeg
                                                                            : ObjectClass::kTableLeg;
}

}  // namespace

std::vector<SimLabelledCluster> labelSimScan(const sim::LaserScan& scan, const sim::Pose2& laser_pose,
                                             const std::vector<sim::PersonState>& people, const sim::World& world,
                                             double t, const SegmentationParams& segmentation,
                                             const SimLabelParams& params, SimLabelStats* stats) {
  // Ground-truth geometry at time t, each piece with its class (person legs carry the person id).
  struct GtCircle {
    sim::Vec2 c;
    double r;
    ObjectClass cls;
    int person;
  };
  struct GtSegment {
    sim::Vec2 a, b;
    ObjectClass cls;
  };
  std::vector<GtCircle> circles;
  std::vector<GtSegment> segments;
  for (const sim::PersonState& p : people)
    for (const sim::Vec2& leg : p.legs) circles.push_back({leg, p.leg_radius, ObjectClass::kPersonLeg, p.id});
  for (const sim::Door& d : world.doors) {
    const sim::Segment s = d.panel(t);
    segments.push_back({s.a, s.b, ObjectClass::kDoor});
  }
  for (const sim::Furniture& f : world.furniture) {
    std::vector<sim::Segment> fs;
    std::vector<sim::Circle> fc;
    f.geometry(t, fs, fc);
    for (const sim::Circle& c : fc) circles.push_back({c.center, c.radius, furnitureLegClass(f), -1});
    for (const sim::Segment& s : fs) segments.push_back({s.a, s.b, ObjectClass::kClutter});
  }
  for (const sim::Marker& m : world.markers) circles.push_back({m.position, m.radius, ObjectClass::kPole, -1});
  for (const sim::Segment& s : world.walls) segments.push_back({s.a, s.b, ObjectClass::kWall});

  const LaserScan ls = fromSimScan(scan);
  const Pose2 lp{laser_pose.x, laser_pose.y, laser_pose.theta};
  std::vector<SimLabelledCluster> out;
  if (stats) ++stats->scans;
  for (const Cluster& c : segmentScan(ls, segmentation)) {
    if (c.centroid().norm() > params.max_range) {
      if (stats) ++stats->far;
      continue;
    }
    std::size_t on_person = 0;
    std::map<int, std::size_t> person_votes;
    std::map<ObjectClass, std::size_t> class_votes;
    for (const Eigen::Vector2d& q : c.points) {
      const Eigen::Vector2d p = lp.transform(q);
      double best = params.surface_tolerance;
      const GtCircle* best_circle = nullptr;
      ObjectClass best_cls = ObjectClass::kClutter;  // returns on nothing known (outliers) count as clutter
      for (const GtCircle& g : circles) {
        const double d = circleDistance(p, g.c, g.r);
        if (d < best) best = d, best_circle = &g, best_cls = g.cls;
      }
      for (const GtSegment& g : segments) {
        const double d = segmentDistance(p, g.a, g.b);
        if (d < best) best = d, best_circle = nullptr, best_cls = g.cls;
      }
      if (best_cls == ObjectClass::kPersonLeg) {
        ++on_person;
        ++person_votes[best_circle->person];
      } else {
        ++class_votes[best_cls];
      }
    }
    const double share = double(on_person) / double(c.points.size());
    SimLabelledCluster s;
    s.sample.features = computeFeatures(c);
    s.world_centroid = lp.transform(c.centroid());
    if (share >= params.positive_share) {
      s.sample.positive = true;
      s.sample.object_class = ObjectClass::kPersonLeg;
      s.person = std::max_element(person_votes.begin(), person_votes.end(),
                                  [](const auto& a, const auto& b) { return a.second < b.second; })->first;
      if (stats) ++stats->positives;
    } else if (share <= params.negative_share) {
      s.sample.positive = false;
      s.sample.object_class = std::max_element(class_votes.begin(), class_votes.end(), [](const auto& a, const auto& b) {
                                return a.second < b.second;
                              })->first;
      if (stats) ++stats->negatives;
    } else {
      if (stats) ++stats->ambiguous;
      continue;  // a leg merged with furniture or a wall: neither label is true
    }
    out.push_back(s);
  }
  return out;
}

namespace {

sim::Region squareAround(sim::Vec2 c, double half) {
  sim::Region r;
  r.name = "around";
  r.polygon = {{c.x - half, c.y - half}, {c.x + half, c.y - half}, {c.x + half, c.y + half}, {c.x - half, c.y + half}};
  return r;
}

sim::Region worldRegion(const sim::World& w, sim::Rng& rng) {
  if (!w.regions.empty()) {
    const std::size_t i = std::min(w.regions.size() - 1, std::size_t(rng.uniform() * double(w.regions.size())));
    return w.regions[i];
  }
  sim::Region r;
  r.polygon = {w.bounds_min, {w.bounds_max.x, w.bounds_min.y}, w.bounds_max, {w.bounds_min.x, w.bounds_max.y}};
  return r;
}

// "open": a walled empty hall (side x side m), like the open areas of pedestrian data sets (no furniture of its
// own; the episode adds some).
sim::World openHall(double side) {
  sim::World w;
  w.name = "open";
  const sim::Vec2 c[4] = {{0, 0}, {side, 0}, {side, side}, {0, side}};
  for (int i = 0; i < 4; ++i) w.walls.push_back({c[i], c[(i + 1) % 4]});
  w.regions.push_back({"hall", {{2, 2}, {side - 2, 2}, {side - 2, side - 2}, {2, side - 2}}});
  w.computeBounds();
  return w;
}

int uniformInt(sim::Rng& rng, int lo, int hi) {
  return lo + std::min(hi - lo, int(rng.uniform() * double(hi - lo + 1)));
}

}  // namespace

std::vector<SimLabelledCluster> simLabelledClusters(const SimTrainingParams& params, SimLabelStats* stats) {
  if (params.worlds.empty()) throw InputError("gen-train: no worlds given");
  std::vector<sim::World> worlds;
  for (const std::string& w : params.worlds) worlds.push_back(w == "open" ? openHall(30.0) : sim::loadWorld(sim::resolveWorldPath(w)));
  std::vector<SimLabelledCluster> out;
  const sim::Rng root(params.seed);
  for (int k = 0; k < params.episodes; ++k) {
    sim::Rng rng = root.fork(static_cast<std::uint64_t>(k));
    sim::World world = worlds[static_cast<std::size_t>(uniformInt(rng, 0, int(worlds.size()) - 1))];
    world.people.clear();
    world.crowd.reset();
    sim::Vec2 start;
    {
      const sim::FreeSpaceGrid free(world);
      bool found = false;
      for (int tries = 0; tries < 20 && !found; ++tries) found = free.samplePoint(worldRegion(world, rng), rng, start);
      if (!found) continue;
      // Extra furniture around the robot (legs-only tables and chairs, clutter boxes), not on top of the robot.
      const sim::Region around = squareAround(start, params.walker_area);
      auto place = [&](const std::string& name, double length, double width, bool legs_only, double leg_radius) {
        sim::Vec2 p;
        if (!free.samplePoint(around, rng, p) || sim::norm(p - start) < 0.8) return;
        sim::Furniture f;
        f.name = name;
        f.length = length;
        f.width = width;
        f.legs_only = legs_only;
        f.leg_radius = leg_radius;
        f.poses = {sim::Pose2{p.x, p.y, rng.uniform(-std::numbers::pi, std::numbers::pi)}};
        world.furniture.push_back(f);
      };
      for (int i = uniformInt(rng, 0, params.max_extra_tables); i > 0; --i)
        place("table_extra", rng.uniform(0.7, 1.8), rng.uniform(0.5, 1.0), true, rng.uniform(0.02, 0.04));
      for (int i = uniformInt(rng, 0, params.max_extra_chairs); i > 0; --i) {
        const double s = rng.uniform(0.36, 0.48);
        place("chair_extra", s, s, true, rng.uniform(0.01, 0.02));
      }
      for (int i = uniformInt(rng, 0, params.max_extra_boxes); i > 0; --i)
        place("box_extra", rng.uniform(0.15, 0.7), rng.uniform(0.15, 0.6), false, 0.0);
    }
    // Walkers on paths planned through free space (now including the extra furniture), looping back to the start.
    const sim::FreeSpaceGrid free(world);
    const sim::Region around = squareAround(start, params.walker_area);
    for (int i = uniformInt(rng, params.min_walkers, params.max_walkers); i > 0; --i) {
      std::vector<sim::Vec2> goals(static_cast<std::size_t>(uniformInt(rng, 2, 3)));
      bool ok = true;
      for (sim::Vec2& g : goals) ok = ok && free.samplePoint(around, rng, g);
      if (!ok) continue;
      goals.push_back(goals.front());
      sim::PeopleSource w;
      w.kind = "scripted";
      for (std::size_t j = 0; j + 1 < goals.size() && ok; ++j) {
        const std::vector<sim::Vec2> path = free.plan(goals[j], goals[j + 1]);
        ok = path.size() >= 2;
        if (ok) w.waypoints.insert(w.waypoints.end(), path.begin() + (w.waypoints.empty() ? 0 : 1), path.end());
      }
      if (!ok) continue;
      w.speed = rng.uniform() < 0.15 ? rng.uniform(0.05, 0.3) : rng.uniform(0.3, 1.5);  // some nearly standing
      world.people.push_back(w);
    }

    sim::SimConfig cfg;
    cfg.seed = rng.next();
    cfg.crowd = false;
    cfg.start = sim::Pose2{start.x, start.y, rng.uniform(-std::numbers::pi, std::numbers::pi)};
    const double res_deg =
        params.resolutions_deg.empty()
            ? 0.5
            : params.resolutions_deg[static_cast<std::size_t>(uniformInt(rng, 0, int(params.resolutions_deg.size()) - 1))];
    cfg.laser.resolution = res_deg * std::numbers::pi / 180.0;
    // Body variety (the simulator's default walker has one leg radius and hip width): drawn per episode.
    cfg.gait.leg_radius = rng.uniform(params.leg_radius_min, params.leg_radius_max);
    cfg.gait.hip_half_width = rng.uniform(params.hip_half_width_min, params.hip_half_width_max);
    cfg.gait.swing_amplitude = rng.uniform(0.2, 0.35);
    cfg.laser.noise_sigma = params.noise_sigma;
    cfg.laser.dropout_prob = params.dropout_prob;
    const sim::Twist2 cmd = rng.uniform() < 0.5 ? sim::Twist2{} : sim::Twist2{rng.uniform(0.1, 0.5), rng.uniform(-0.4, 0.4)};
    sim::Simulator s(world, cfg);
    sim::SimOutput scratch;
    auto advance = [&](double duration) {
      const double end = s.time() + duration;
      while (s.time() < end - 1e-9) {
        s.setCommand(cmd);
        s.advance(std::min(0.1, end - s.time()), scratch);
      }
      scratch = {};
    };
    advance(params.warmup);
    for (int j = 0; j < params.scans_per_episode; ++j) {
      // Step physics until a scan falls due; the people and pose captured before that step are what it saw.
      for (;;) {
        const std::vector<sim::PersonState> people = s.people();
        const sim::Pose2 pose = s.groundTruth();
        const double t = s.time();
        s.setCommand(cmd);
        s.advance(cfg.physics_dt, scratch);
        if (scratch.scans.empty()) continue;
        for (SimLabelledCluster& c : labelSimScan(scratch.scans.back(), sim::compose(pose, cfg.laser.mount), people,
                                                  world, t, params.segmentation, params.label, stats)) {
          c.sample.scene = k;
          out.push_back(std::move(c));
        }
        scratch = {};
        break;
      }
      advance(params.scan_spacing);
    }
  }
  return out;
}

}  // namespace cairn::people_tracking
