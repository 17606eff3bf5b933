// cairn people mask-bench: does person masking help SLAM? (Yuan §3.2.1, Tables 3.1/3.2: 48-67 % lower position
// error with the guide masked.) A guide walks the world's home-tour route ahead of the robot in the simulator
// (components/sim); the robot follows the same route. The same scans feed two GraphSlam instances: raw, and with
// the guide's beams set to NaN by the people pipeline (detectLegs -> PeopleTracker::updateLegs -> GuideTracker
// -> maskScan). Both trajectories are scored against ground truth in the same run. Tool only: the core does not
// depend on the SLAM or the simulator.
#include "tool_mask_bench.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
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

namespace gs = cairn::graph_slam;
namespace sim = cairn::sim;
using namespace cairn::people_tracking;

namespace {

struct MaskBenchParams {
  std::string world = "apartment";
  std::string route = "home_tour";
  std::uint64_t seed = 1;
  double speed = 0.5;       // m/s, guide and robot
  double lead = 1.2;        // m, guide starts this far ahead along the route
  double max_duration = 400.0;
  double heading_drift = 0.03;  // rad/m, odometry heading drift (as in the SLAM pipeline test): SLAM must match
  double scale_error = 0.03;    // odometry scale error
  bool json = false;
};

const sim::Odometry& nearest(const std::vector<sim::Odometry>& v, double t) {
  auto it = std::lower_bound(v.begin(), v.end(), t, [](const sim::Odometry& o, double s) { return o.stamp < s; });
  if (it == v.end()) return v.back();
  if (it != v.begin() && std::abs((it - 1)->stamp - t) < std::abs(it->stamp - t)) --it;
  return *it;
}

struct TrajectoryError {
  double rmse = 0.0, mean = 0.0, max = 0.0;
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
  return e;
}

gs::SlamOptions slamOptions(const sim::Pose2& mount) {
  gs::SlamOptions o;
  o.use_verifier = false;  // the shipped verifier is trained on 180° real scans; this is a 360° simulated laser
  o.loop_min_time_gap = 10.0;
  o.sensor_in_base = gs::Pose2{{mount.x, mount.y}, mount.theta};
  return o;
}

int run(const MaskBenchParams& p) {
  sim::World world = sim::loadWorld(sim::resolveWorldPath(p.world));
  const auto rt = world.routes.find(p.route);
  if (rt == world.routes.end() || rt->second.size() < 2)
    throw InputError("world '" + p.world + "' has no route '" + p.route + "' with at least two waypoints");
  const std::vector<sim::Vec2> route = rt->second;
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

  sim::SimConfig cfg;
  cfg.seed = p.seed;
  cfg.crowd = false;
  cfg.odometry.heading_drift = p.heading_drift;
  cfg.odometry.scale_error = p.scale_error;
  cfg.start = sim::Pose2{route[0].x, route[0].y, std::atan2(r1.y() - r0.y(), r1.x() - r0.x())};
  sim::Simulator s(world, cfg);
  sim::RouteConfig rc;
  rc.speed = p.speed;
  s.followRoute(route, rc);
  sim::SimOutput out;
  while (s.routeActive() && s.time() < p.max_duration) s.advance(1.0, out);
  if (out.scans.empty()) throw InputError("simulation produced no scans");

  const sim::Pose2 mount = cfg.laser.mount;
  gs::GraphSlam raw(slamOptions(mount)), masked(slamOptions(mount));
  auto classifier = std::make_shared<const LegClassifier>(
      LegClassifier::load(defaultModelPath(ClassifierKind::kAdaBoost, "arras14")));
  const PersonDetector detector(classifier);
  PeopleTracker tracker;
  GuideTracker guider;
  std::size_t tracking_scans = 0, masked_beams = 0;
  for (const sim::LaserScan& scan : out.scans) {
    const sim::Pose2& o = nearest(out.odometry, scan.stamp).pose;
    raw.addScan(scan, gs::Pose2{{o.x, o.y}, o.theta});

    LaserScan ls;
    ls.stamp = scan.stamp;
    ls.angle_min = scan.angle_min;
    ls.angle_increment = scan.angle_increment;
    ls.range_min = scan.range_min;
    ls.range_max = scan.range_max;
    ls.ranges = scan.ranges;
    const Pose2 base{o.x, o.y, o.theta};
    const Eigen::Vector2d lp = base.transform({mount.x, mount.y});
    const Pose2 sensor{lp.x(), lp.y(), o.theta + mount.theta};
    tracker.updateLegs(scan.stamp, detector.detectLegs(ls), sensor, detector.params(), &ls);
    const std::vector<Track> tracks = tracker.outputTracks();
    if (guider.state() == GuideState::kSearch) guider.selectClosestInFront(tracks, sensor, scan.stamp);
    const GuideStatus st = guider.update(tracks, sensor, scan.stamp);
    sim::LaserScan filtered = scan;
    if (st.state == GuideState::kTracking) {
      for (const Track& t : tracks)
        if (t.id == guider.guideId()) {
          masked_beams += maskScan(ls, {{sensor.inverseTransform(t.position()), personRadius(t.leg_separation)}});
          filtered.ranges = ls.ranges;
          ++tracking_scans;
        }
    }
    masked.addScan(filtered, gs::Pose2{{o.x, o.y}, o.theta});
  }
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
  const double ratio = er.rmse > 0 ? em.rmse / er.rmse : 0.0;
  const double guide_frac = double(tracking_scans) / double(out.scans.size());
  if (p.json) {
    std::printf(
        "{\"world\": \"%s\", \"route\": \"%s\", \"seed\": %llu, \"speed\": %.2f, \"duration_s\": %.1f, \"scans\": %zu, "
        "\"guide_tracked_fraction\": %.3f, \"masked_beams_per_tracked_scan\": %.1f, "
        "\"odometry\": {\"ate_rmse\": %.4f, \"ate_mean\": %.4f, \"ate_max\": %.4f}, "
        "\"slam_unmasked\": {\"ate_rmse\": %.4f, \"ate_mean\": %.4f, \"ate_max\": %.4f}, "
        "\"slam_masked\": {\"ate_rmse\": %.4f, \"ate_mean\": %.4f, \"ate_max\": %.4f}, "
        "\"masked_over_unmasked\": %.3f, \"reduction_percent\": %.1f}\n",
        p.world.c_str(), p.route.c_str(), static_cast<unsigned long long>(p.seed), p.speed, s.time(), out.scans.size(),
        guide_frac, tracking_scans ? double(masked_beams) / double(tracking_scans) : 0.0, eo.rmse, eo.mean, eo.max,
        er.rmse, er.mean, er.max, em.rmse, em.mean, em.max, ratio, 100.0 * (1.0 - ratio));
  } else {
    std::printf("%s / %s, seed %llu: %.0f s, %zu scans, guide tracked and masked in %.0f %% of the scans\n",
                p.world.c_str(), p.route.c_str(), static_cast<unsigned long long>(p.seed), s.time(), out.scans.size(),
                100.0 * guide_frac);
    std::printf("  position error (ATE RMSE): odometry %.3f m, SLAM unmasked %.3f m, SLAM masked %.3f m (ratio %.2f, "
                "%.0f %% lower)\n", eo.rmse, er.rmse, em.rmse, ratio, 100.0 * (1.0 - ratio));
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
    auto number = [&](const std::string& v) {
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0') throw InputError("option " + a + " expects a number, got '" + v + "'");
      return x;
    };
    if (a == "--json") p.json = true;
    else if (a == "--world") p.world = value();
    else if (a == "--route") p.route = value();
    else if (a == "--seed") p.seed = static_cast<std::uint64_t>(number(value()));
    else if (a == "--speed") p.speed = number(value());
    else if (a == "--lead") p.lead = number(value());
    else if (a == "--heading-drift") p.heading_drift = number(value());
    else if (a == "--scale-error") p.scale_error = number(value());
    else if (a == "--max-duration") p.max_duration = number(value());
    else throw InputError("unknown mask-bench option '" + a + "'");
  }
  if (!(p.speed > 0.05 && p.speed < 3.0)) throw InputError("--speed must be in (0.05, 3) m/s");
  return run(p);
}
