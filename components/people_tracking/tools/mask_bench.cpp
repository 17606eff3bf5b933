// cairn people mask-bench: does person masking help SLAM? (Yuan §3.2.1, Tables 3.1/3.2: 48-67 % lower position
// error with the guide masked.) A guide walks a tour of the world ahead of the robot in the simulator
// (components/sim). By default the robot follows the guide as in Yuan's experiments (§3.2.1, person following of
// §2.2): the guide is the tracker's guide (GuideTracker, closest in front), and the robot drives along the guide's
// tracked trail (so it does not cut corners at doorways) until it is `follow_distance` behind the guide, turning
// towards the trail point ahead (direction following, Yuan §2.2). `--robot route` keeps the old setting (the robot
// drives the route on its own). The same scans feed two GraphSlam instances: raw, and with the guide's beams set
// to NaN by the people pipeline (detectLegs -> PeopleTracker::updateLegs -> GuideTracker -> maskScan). Both
// trajectories are scored against ground truth in the same run. Tool only: the core does not depend on the SLAM
// or the simulator.
#include "mask_bench.hpp"

#include "cli_parse.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "cairn/graph_slam/slam.hpp"
#include "cairn/people_tracking/classifier.hpp"
#include "cairn/people_tracking/detector.hpp"
#include "cairn/people_tracking/guide.hpp"
#include "cairn/people_tracking/masking.hpp"
#include "cairn/people_tracking/tracker.hpp"
#include "cairn/sim/simulator.hpp"
#include "cairn/sim/world.hpp"
#include "sim_training.hpp"

namespace gs = cairn::graph_slam;
namespace sim = cairn::sim;

namespace cairn::people_tracking {
namespace {


const sim::Odometry& nearest(const std::vector<sim::Odometry>& v, double t) {
  auto it = std::lower_bound(v.begin(), v.end(), t, [](const sim::Odometry& o, double s) { return o.stamp < s; });
  if (it == v.end()) return v.back();
  if (it != v.begin() && std::abs((it - 1)->stamp - t) < std::abs(it->stamp - t)) --it;
  return *it;
}

struct TrajectoryError : MaskBenchError {
  // The alignment: world = R (p - ca) + cb for a point p of the SLAM (map) frame.
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
  Eigen::Vector2d ca = Eigen::Vector2d::Zero(), cb = Eigen::Vector2d::Zero();
};

// Absolute trajectory error after the least-squares rigid 2D alignment of the SLAM poses to the truth.
TrajectoryError trajectoryError(const std::vector<gs::StampedPose>& traj, const std::vector<sim::Odometry>& truth) {
  std::vector<Eigen::Vector2d> a, b;
  for (const auto& p : traj) {
    const sim::Pose2& g = nearest(truth, p.stamp).pose;
    a.push_back(p.pose.t);
    b.emplace_back(g.x, g.y);
  }
  TrajectoryError e;
  if (a.empty()) return e;
  Eigen::Vector2d ca = Eigen::Vector2d::Zero(), cb = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) ca += a[i], cb += b[i];
  ca /= double(a.size());
  cb /= double(b.size());
  double sxx = 0.0, sxy = 0.0;  // rotation maximising sum b_i . R a_i
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector2d p = a[i] - ca, q = b[i] - cb;
    sxx += p.dot(q);
    sxy += p.x() * q.y() - p.y() * q.x();
  }
  const double th = std::atan2(sxy, sxx);
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(th).toRotationMatrix();
  double sum2 = 0.0, sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = (R * (a[i] - ca) + cb - b[i]).norm();
    sum2 += d * d;
    sum += d;
    e.max = std::max(e.max, d);
  }
  e.rmse = std::sqrt(sum2 / double(a.size()));
  e.mean = sum / double(a.size());
  e.R = R;
  e.ca = ca;
  e.cb = cb;
  return e;
}

// Map errors of a SLAM map against the simulator's static geometry (Yuan §3.2.2, Figs. 3.4-3.6: with the guide's
// legs in the scans the map gets leg imprints, false obstacles on which NF1 finds no path). An occupied cell
// (p >= occupied_thresh) whose centre, aligned to the world with the trajectory alignment, lies farther than
// `tolerance` from every wall, door and piece of furniture is spurious; spurious cells within `guide_radius` of
// the guide's true path are leg imprints.
MaskBenchMap mapError(const gs::OccupancyGrid& map, const TrajectoryError& align, const sim::Simulator& s,
                      const std::vector<Eigen::Vector2d>& guide_path, double occupied_thresh = 0.65,
                      double tolerance = 0.15, double guide_radius = 0.5) {
  MaskBenchMap e;
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      if (map.at(x, y) < 100.0 * occupied_thresh) continue;  // unknown (-1) and free cells
      ++e.occupied;
      const Eigen::Vector2d c = map.origin + map.resolution * Eigen::Vector2d(x + 0.5, y + 0.5);
      const Eigen::Vector2d w = align.R * (c - align.ca) + align.cb;
      if (s.obstacleClearance({w.x(), w.y()}, 2.0 * tolerance) <= tolerance) continue;
      ++e.spurious;
      for (const auto& g : guide_path)
        if ((g - w).squaredNorm() < guide_radius * guide_radius) {
          ++e.imprints;
          break;
        }
    }
  return e;
}

gs::SlamOptions slamOptions(const sim::Pose2& mount) {
  gs::SlamOptions o;
  o.use_verifier = false;  // the shipped verifier is trained on 180° real scans; this is a 360° simulated laser
  o.loop_min_time_gap = 10.0;
  o.sensor_in_base = gs::Pose2{{mount.x, mount.y}, mount.theta};
  return o;
}

// Removes out-and-back spurs (a -> b -> a) so that the guide never turns round and walks back past a following
// robot; repeated until none is left.
std::vector<sim::Vec2> withoutSpurs(std::vector<sim::Vec2> r) {
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = 1; i + 1 < r.size(); ++i)
      if (sim::norm(r[i + 1] - r[i - 1]) < 1e-6) {
        r.erase(r.begin() + static_cast<long>(i), r.begin() + static_cast<long>(i) + 2);
        changed = true;
        break;
      }
  }
  return r;
}

}  // namespace

MaskBenchResult runMaskBench(const MaskBenchParams& p) {
  sim::World world = sim::loadWorld(sim::resolveWorldPath(p.world));
  const auto rt = world.routes.find(p.route);
  if (rt == world.routes.end() || rt->second.size() < 2)
    throw InputError("world '" + p.world + "' has no route '" + p.route + "' with at least two waypoints");
  const std::vector<sim::Vec2> route = p.keep_spurs ? rt->second : withoutSpurs(rt->second);
  if (route.size() < 2) throw InputError("route '" + p.route + "' has fewer than two waypoints without its spurs");
  // Only the guide: no crowd, no recorded people. The guide starts `lead` metres ahead on the first leg.
  world.crowd.reset();
  world.people.clear();
  sim::PeopleSource guide;
  guide.kind = "scripted";
  const Eigen::Vector2d r0(route[0].x, route[0].y), r1(route[1].x, route[1].y);
  const double first = (r1 - r0).norm();
  const Eigen::Vector2d g0 = r0 + std::min(p.lead, 0.9 * first) * (r1 - r0) / std::max(first, 1e-9);
  guide.waypoints.push_back({g0.x(), g0.y()});
  guide.waypoints.insert(guide.waypoints.end(), route.begin() + 1, route.end());
  guide.speed = p.speed;
  world.people.push_back(guide);
  double tour_length = 0.0;
  for (std::size_t i = 1; i < guide.waypoints.size(); ++i)
    tour_length += sim::norm(guide.waypoints[i] - guide.waypoints[i - 1]);

  sim::SimConfig cfg;
  cfg.seed = p.seed;
  cfg.crowd = false;
  cfg.odometry.heading_drift = p.heading_drift;
  cfg.odometry.scale_error = p.scale_error;
  cfg.laser.fov = p.fov_deg * M_PI / 180.0;
  cfg.laser.range_max = p.range_max;
  cfg.start = sim::Pose2{route[0].x, route[0].y, std::atan2(r1.y() - r0.y(), r1.x() - r0.x())};
  sim::Simulator s(world, cfg);
  if (!p.follow) {
    sim::RouteConfig rc;
    rc.speed = p.speed;
    s.followRoute(route, rc);
  }
  // Following: the guide's tour plus time to catch up; route mode: until the route is done.
  const double duration = std::min(p.max_duration, p.follow ? tour_length / p.speed + 3.0 : p.max_duration);

  const sim::Pose2 mount = cfg.laser.mount;
  gs::GraphSlam raw(slamOptions(mount)), masked(slamOptions(mount));
  auto classifier = std::make_shared<const LegClassifier>(
      LegClassifier::load(p.model.empty() ? defaultModelPath(ClassifierKind::kAdaBoost, "arras14") : p.model));
  const PersonDetector detector(classifier, p.detector);
  MotionEvidence motion;  // as the component: earlier scans in the odometry frame
  PeopleTracker tracker;
  GuideTracker guider;
  std::size_t tracking_scans = 0, masked_beams = 0, guide_in_field = 0, stalled_scans = 0;
  double travelled = 0.0, guide_distance_sum = 0.0;
  int stall_run = 0, recovery_scans = 0;
  std::size_t recoveries = 0;
  std::vector<Eigen::Vector2d> guide_path;  // the guide's true positions at the scans (map-error diagnostics)
  std::deque<Eigen::Vector2d> trail;  // the guide's tracked positions (odometry frame) still ahead of the robot
  sim::SimOutput out;
  std::size_t next_scan = 0;
  sim::Twist2 cmd;
  sim::Pose2 last_truth = s.groundTruth();
  while (p.follow ? s.time() < duration : (s.routeActive() && s.time() < duration)) {
    s.setCommand(cmd);
    s.advance(1.0 / cfg.laser.rate, out);
    const sim::Pose2 truth = s.groundTruth();
    const double step = std::hypot(truth.x - last_truth.x, truth.y - last_truth.y);
    travelled += step;
    last_truth = truth;
    for (; next_scan < out.scans.size(); ++next_scan) {
      const sim::LaserScan& scan = out.scans[next_scan];
      const sim::Pose2& o = nearest(out.odometry, scan.stamp).pose;
      raw.addScan(scan, gs::Pose2{{o.x, o.y}, o.theta});

      LaserScan ls = fromSimScan(scan);
      const Pose2 base{o.x, o.y, o.theta};
      const Pose2 sensor = base * Pose2{mount.x, mount.y, mount.theta};
      const std::vector<LegDetection> legs = detector.detectLegs(ls, &motion, sensor);
      motion.add(ls, sensor);
      tracker.updateLegs(scan.stamp, legs, sensor, detector.params(), &ls);
      const std::vector<Track>& tracks = tracker.tracks();  // coasting ones too, as the component (guide.lost_timeout)
      if (guider.state() == GuideState::kSearch) guider.selectClosestInFront(tracks, sensor, scan.stamp);
      const GuideStatus st = guider.update(tracks, sensor, scan.stamp);
      sim::LaserScan filtered = scan;
      if (st.state == GuideState::kTracking && st.track) {
        masked_beams += maskScan(ls, {{sensor.inverseTransform(st.track->position()), personRadius(st.track->leg_separation)}}, p.mask);
        filtered.ranges = ls.ranges;
        ++tracking_scans;
        if (trail.empty() || (trail.back() - st.track->position()).norm() > 0.1) trail.push_back(st.track->position());
      }
      masked.addScan(filtered, gs::Pose2{{o.x, o.y}, o.theta});

      // Ground-truth diagnostics: is the guide in Yuan's field (front semicircle, 8 m) of the robot?
      if (!s.people().empty()) {
        const sim::Vec2 g = s.people().front().position;
        guide_path.emplace_back(g.x, g.y);
        const double dx = g.x - truth.x, dy = g.y - truth.y;
        const double ahead = std::cos(truth.theta) * dx + std::sin(truth.theta) * dy;
        guide_in_field += ahead > 0.0 && std::hypot(dx, dy) < 8.0;
        guide_distance_sum += std::hypot(dx, dy);
      }
      const bool stalled = p.follow && cmd.v > 0.05 && step < 0.2 * cmd.v / cfg.laser.rate;
      stalled_scans += stalled;
      stall_run = stalled ? stall_run + 1 : 0;

      if (!p.follow) continue;
      // Follow the guide's trail (odometry frame): drop trail points the robot has reached, steer to the next
      // one, drive while the guide is farther than follow_distance. Without a guide, finish the trail slowly
      // (the guide went that way: re-acquisition) and then stop.
      const Eigen::Vector2d rb(o.x, o.y);
      while (trail.size() > 1 && (trail.front() - rb).norm() < 0.35) trail.pop_front();
      cmd = {};
      // Recovery: in contact with furniture for 3 scans, back off for 0.5 s.
      if (stall_run >= 3) recovery_scans = 5;
      if (recovery_scans > 0) {
        --recovery_scans;
        cmd.v = -0.2;
        ++recoveries;
        continue;
      }
      if (!trail.empty()) {
        // Direction to the next trail point plus a repulsion from returns closer than `clear` (potential field;
        // the robot, 0.28 m footprint, is wider than the guide whose trail it drives). The guide's own beams are
        // NaN in `ls` while it is tracked, so the guide does not repel.
        const Eigen::Vector2d to_world = trail.front() - rb;
        Eigen::Vector2d dir = base.rotation().transpose() * to_world.normalized();
        const double clear = 0.55;
        for (std::size_t i = 0; i < ls.ranges.size(); ++i) {
          if (!ls.valid(i) || ls.ranges[i] > clear + 0.3) continue;
          const Eigen::Vector2d q = Eigen::Vector2d(mount.x, mount.y) + Eigen::Rotation2Dd(mount.theta) * ls.point(i);
          const double d = q.norm();
          if (d < clear && d > 1e-3 && q.x() > -0.1) dir -= 0.08 * (clear - d) / clear * q / d;
        }
        const double bearing = std::atan2(dir.y(), dir.x());
        const bool tracking = st.state == GuideState::kTracking && st.track;
        const double gap = tracking ? (st.track->position() - rb).norm() - p.follow_distance
                                    : (trail.back() - rb).norm() - 0.35;
        const double v_lim = tracking ? p.max_v : 0.5 * p.max_v;
        cmd.v = std::clamp(0.8 * gap, 0.0, v_lim) * std::max(0.0, std::cos(bearing));
        cmd.w = std::clamp(1.5 * bearing, -p.max_w, p.max_w);
        if (!tracking && gap <= 0.0) trail.clear();
      }
    }
  }
  if (out.scans.empty()) throw InputError("simulation produced no scans");
  raw.finish();
  masked.finish();
  const TrajectoryError er = trajectoryError(raw.trajectory(), out.ground_truth);
  const TrajectoryError em = trajectoryError(masked.trajectory(), out.ground_truth);
  std::vector<gs::StampedPose> odom_traj;
  for (const auto& sc : out.scans) {
    const sim::Pose2& o = nearest(out.odometry, sc.stamp).pose;
    odom_traj.push_back({sc.stamp, gs::Pose2{{o.x, o.y}, o.theta}});
  }
  const TrajectoryError eo = trajectoryError(odom_traj, out.ground_truth);
  const MaskBenchMap mr = mapError(raw.map(), er, s, guide_path), mm = mapError(masked.map(), em, s, guide_path);
  MaskBenchResult r;
  r.duration = s.time();
  r.scans = out.scans.size();
  r.travelled = travelled;
  const double n_scans = double(out.scans.size());
  r.guide_in_field = double(guide_in_field) / n_scans;
  r.guide_mean_distance = guide_distance_sum / n_scans;
  r.stalled = double(stalled_scans) / n_scans;
  r.recovery_scans = recoveries;
  r.guide_tracked = double(tracking_scans) / n_scans;
  r.masked_beams_per_tracked_scan = tracking_scans ? double(masked_beams) / double(tracking_scans) : 0.0;
  r.odometry = eo;
  r.unmasked = er;
  r.masked = em;
  r.map_unmasked = mr;
  r.map_masked = mm;
  return r;
}

namespace {

int printMaskBench(const MaskBenchParams& p, const MaskBenchResult& r) {
  const double ratio = r.unmasked.rmse > 0 ? r.masked.rmse / r.unmasked.rmse : 0.0;
  const char* mask = p.mask == MaskMode::kTangents ? "tangents" : "inside";
  const auto& eo = r.odometry;
  const auto& er = r.unmasked;
  const auto& em = r.masked;
  const auto& mr = r.map_unmasked;
  const auto& mm = r.map_masked;
  if (p.json) {
    std::printf(
        "{\"world\": \"%s\", \"route\": \"%s\", \"robot\": \"%s\", \"seed\": %llu, \"speed\": %.2f, \"duration_s\": %.1f, "
        "\"scans\": %zu, \"robot_travelled_m\": %.1f, \"guide_in_field_fraction\": %.3f, \"guide_mean_distance_m\": %.2f, "
        "\"stalled_fraction\": %.3f, \"recovery_scans\": %zu, \"guide_tracked_fraction\": %.3f, \"masked_beams_per_tracked_scan\": %.1f, "
        "\"odometry\": {\"ate_rmse\": %.4f, \"ate_mean\": %.4f, \"ate_max\": %.4f}, "
        "\"slam_unmasked\": {\"ate_rmse\": %.4f, \"ate_mean\": %.4f, \"ate_max\": %.4f}, "
        "\"slam_masked\": {\"ate_rmse\": %.4f, \"ate_mean\": %.4f, \"ate_max\": %.4f}, "
        "\"masked_over_unmasked\": %.3f, \"reduction_percent\": %.1f, \"mask\": \"%s\", "
        "\"map_unmasked\": {\"occupied_cells\": %zu, \"spurious_cells\": %zu, \"leg_imprint_cells\": %zu}, "
        "\"map_masked\": {\"occupied_cells\": %zu, \"spurious_cells\": %zu, \"leg_imprint_cells\": %zu}}\n",
        p.world.c_str(), p.route.c_str(), p.follow ? "follow" : "route", static_cast<unsigned long long>(p.seed), p.speed,
        r.duration, r.scans, r.travelled, r.guide_in_field, r.guide_mean_distance, r.stalled, r.recovery_scans,
        r.guide_tracked, r.masked_beams_per_tracked_scan, eo.rmse, eo.mean, eo.max, er.rmse, er.mean, er.max, em.rmse,
        em.mean, em.max, ratio, 100.0 * (1.0 - ratio), mask, mr.occupied, mr.spurious, mr.imprints, mm.occupied,
        mm.spurious, mm.imprints);
  } else {
    std::printf("%s / %s, robot %s, seed %llu: %.0f s, %zu scans, robot drove %.1f m, guide in the front field in "
                "%.0f %% (mean distance %.2f m), tracked and masked in %.0f %% of the scans\n",
                p.world.c_str(), p.route.c_str(), p.follow ? "follows the guide" : "drives the route",
                static_cast<unsigned long long>(p.seed), r.duration, r.scans, r.travelled, 100.0 * r.guide_in_field,
                r.guide_mean_distance, 100.0 * r.guide_tracked);
    std::printf("  position error (ATE RMSE): odometry %.3f m, SLAM unmasked %.3f m, SLAM masked (%s) %.3f m (ratio "
                "%.2f, %.0f %% lower)\n", eo.rmse, er.rmse, mask, em.rmse, ratio, 100.0 * (1.0 - ratio));
    std::printf("  map: spurious occupied cells unmasked %zu (leg imprints %zu), masked %zu (leg imprints %zu)\n",
                mr.spurious, mr.imprints, mm.spurious, mm.imprints);
  }
  return 0;
}

}  // namespace

int runMaskBenchVerb(int argc, char** argv) {
  MaskBenchParams p;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError("option " + a + " needs a value");
      return argv[++i];
    };
    auto number = [&](const std::string& v) { return parseNumber(a, v); };
    if (a == "--json") p.json = true;
    else if (a == "--world") p.world = value();
    else if (a == "--route") p.route = value();
    else if (a == "--seed") p.seed = static_cast<std::uint64_t>(parseInteger(a, value(), 0, kMaxSeed));
    else if (a == "--speed") p.speed = number(value());
    else if (a == "--lead") p.lead = number(value());
    else if (a == "--heading-drift") p.heading_drift = number(value());
    else if (a == "--scale-error") p.scale_error = number(value());
    else if (a == "--max-duration") p.max_duration = number(value());
    else if (a == "--robot") {
      const std::string v = value();
      if (v != "follow" && v != "route") throw InputError("--robot must be follow or route, got '" + v + "'");
      p.follow = v == "follow";
    } else if (a == "--keep-spurs") p.keep_spurs = true;
    else if (a == "--follow-distance") p.follow_distance = number(value());
    else if (a == "--fov-deg") p.fov_deg = number(value());
    else if (a == "--range-max") p.range_max = number(value());
    else if (a == "--model") p.model = value();
    else if (a == "--min-points")
      p.detector.segmentation.min_points =
          static_cast<std::size_t>(parseIntegerParam(a, value(), "segmentation.min_points"));
    else if (a == "--mask") p.mask = parseMaskMode(value(), "--mask");
    else throw InputError("unknown mask-bench option '" + a + "'");
  }
  if (!(p.speed > 0.05 && p.speed < 3.0)) throw InputError("--speed must be in (0.05, 3) m/s");
  if (!(p.fov_deg >= 30.0 && p.fov_deg <= 360.0)) throw InputError("--fov-deg must be in [30, 360]");
  if (!(p.range_max >= 2.0 && p.range_max <= 80.0)) throw InputError("--range-max must be in [2, 80] m");
  if (!(p.follow_distance > 0.3 && p.follow_distance < 5.0)) throw InputError("--follow-distance must be in (0.3, 5) m");
  if (!(p.lead >= 0.0 && p.lead <= 10.0)) throw InputError("--lead must be in [0, 10] m");
  if (!(std::abs(p.heading_drift) <= 0.5)) throw InputError("--heading-drift must be in [-0.5, 0.5] rad/m");
  if (!(std::abs(p.scale_error) < 0.5)) throw InputError("--scale-error must be in (-0.5, 0.5)");
  if (!(p.max_duration > 0.0 && p.max_duration <= 3600.0)) throw InputError("--max-duration must be in (0, 3600] s");
  return printMaskBench(p, runMaskBench(p));
}

}  // namespace cairn::people_tracking
