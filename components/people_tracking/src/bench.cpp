#include "cairn/people_tracking/bench.hpp"
#include "cairn/people_tracking/param_ranges.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>

#include "cairn/people_tracking/classifier.hpp"
#include "cairn/people_tracking/detector.hpp"
#include "cairn/people_tracking/static_map.hpp"
#include "cairn/people_tracking/trajectories.hpp"

namespace cairn::people_tracking {

namespace {

// Baseline: greedy nearest-neighbour association on positions without a motion model (what the
// wg-perception leg_detector-style trackers do), 0.5 m gate, confirmed after 2 hits, dropped after 0.5 s.
class NearestNeighbourTracker {
 public:
  struct T {
    int id;
    Eigen::Vector2d p;
    double last;
    int hits;
  };
  void update(double t, const std::vector<PersonDetection>& dets) {
    std::vector<bool> used(dets.size(), false), matched(tracks_.size(), false);
    std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
    for (std::size_t i = 0; i < tracks_.size(); ++i)
      for (std::size_t j = 0; j < dets.size(); ++j) {
        const double d = (tracks_[i].p - dets[j].position).norm();
        if (d < 0.5) pairs.emplace_back(d, i, j);
      }
    std::sort(pairs.begin(), pairs.end());
    for (const auto& [d, i, j] : pairs) {
      if (matched[i] || used[j]) continue;
      matched[i] = used[j] = true;
      tracks_[i].p = dets[j].position;
      tracks_[i].last = t;
      ++tracks_[i].hits;
    }
    for (std::size_t j = 0; j < dets.size(); ++j)
      if (!used[j]) tracks_.push_back({next_++, dets[j].position, t, 1});
    std::erase_if(tracks_, [&](const T& x) { return t - x.last > 0.5; });
  }
  [[nodiscard]] std::vector<MotObject> confirmed() const {
    std::vector<MotObject> out;
    for (const auto& x : tracks_)
      if (x.hits >= 2) out.push_back({x.id, x.p});
    return out;
  }

 private:
  std::vector<T> tracks_;
  int next_ = 1;
};

struct RobotPath {
  enum Kind { kStatic, kCircle, kFile, kRoute } kind = kStatic;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double heading = 0.0;  // static robot
  double radius = 0.0;
  std::vector<std::pair<double, Pose2>> poses;  // kFile: trajectory time; kRoute: time since the start, one loop

  Pose2 at(double t, double t0) const {
    if (kind == kStatic) return Pose2{center.x(), center.y(), heading};
    if (kind == kCircle) {
      const double w = 0.4 / radius;  // 0.4 m/s
      const double a = w * (t - t0);
      return Pose2{center.x() + radius * std::cos(a), center.y() + radius * std::sin(a), a + M_PI / 2};
    }
    if (kind == kRoute) t = std::fmod(std::max(0.0, t - t0), poses.back().first);
    if (t <= poses.front().first) return poses.front().second;
    if (t >= poses.back().first) return poses.back().second;
    auto hi = std::lower_bound(poses.begin(), poses.end(), t, [](const auto& p, double x) { return p.first < x; });
    auto lo = hi - 1;
    const double s = (t - lo->first) / (hi->first - lo->first);
    const double dth = std::remainder(hi->second.theta - lo->second.theta, 2 * M_PI);
    return Pose2{lo->second.x + s * (hi->second.x - lo->second.x), lo->second.y + s * (hi->second.y - lo->second.y),
                 lo->second.theta + s * dth};
  }
};

// Keyframes of one loop along `route` (closed back to its first point): turn in place at `turn_rate` towards each
// segment, then drive it at `speed`, and at the end turn back to the first heading; times from 0.
std::vector<std::pair<double, Pose2>> routePoses(const std::vector<Eigen::Vector2d>& route, double speed,
                                                 double turn_rate) {
  std::vector<Eigen::Vector2d> pts = route;
  if ((pts.front() - pts.back()).norm() > 1e-9) pts.push_back(pts.front());
  std::vector<std::pair<double, Pose2>> out;
  double t = 0.0;
  const Eigen::Vector2d d0 = pts[1] - pts[0];
  double theta = std::atan2(d0.y(), d0.x());
  out.push_back({t, Pose2{pts[0].x(), pts[0].y(), theta}});
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const Eigen::Vector2d d = pts[i] - pts[i - 1];
    if (d.norm() < 1e-9) continue;
    const double heading = theta + std::remainder(std::atan2(d.y(), d.x()) - theta, 2 * M_PI);
    if (std::abs(heading - theta) > 1e-9) {
      t += std::abs(heading - theta) / turn_rate;
      theta = heading;
      out.push_back({t, Pose2{pts[i - 1].x(), pts[i - 1].y(), theta}});
    }
    t += d.norm() / speed;
    out.push_back({t, Pose2{pts[i].x(), pts[i].y(), theta}});
  }
  const double first = out.front().second.theta;
  const double back = theta + std::remainder(first - theta, 2 * M_PI);
  if (std::abs(back - theta) > 1e-9) {
    t += std::abs(back - theta) / turn_rate;
    out.push_back({t, Pose2{pts.back().x(), pts.back().y(), back}});
  }
  return out;
}

RobotPath parseRobotPath(const std::string& spec, const Eigen::Vector2d& center,
                         const std::vector<Eigen::Vector2d>& route, double route_speed) {
  RobotPath r;
  r.center = center;
  if (spec.empty()) return r;
  if (spec.rfind("route:", 0) == 0) {
    if (route.size() < 2) throw InputError("robot path '" + spec + "': needs a route of the world (--world with that route)");
    if (!(route_speed > 0.0)) throw InputError("robot path '" + spec + "': route speed must be > 0");
    r.kind = RobotPath::kRoute;
    r.poses = routePoses(route, route_speed, 1.0);
    if (!(r.poses.back().first > 0.0)) throw InputError("robot path '" + spec + "': the route has no length");
    return r;
  }
  if (spec.rfind("circle:", 0) == 0) {
    r.kind = RobotPath::kCircle;
    try {
      r.radius = std::stod(spec.substr(7));
    } catch (const std::exception&) {
      throw InputError("robot path '" + spec + "': expected circle:<radius>");
    }
    if (!(r.radius > 0.1)) throw InputError("robot path '" + spec + "': radius must be > 0.1 m");
    return r;
  }
  std::ifstream in(spec);
  if (!in) throw InputError("cannot open robot path " + spec);
  r.kind = RobotPath::kFile;
  std::string line;
  std::size_t ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty() || line[0] == '#' || (ln == 1 && line.find('t') != std::string::npos)) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream f(line);
    double t, x, y, th;
    if (!(f >> t >> x >> y >> th)) throw InputError(spec + ":" + std::to_string(ln) + ": expected t,x,y,theta");
    if (!r.poses.empty() && t <= r.poses.back().first)
      throw InputError(spec + ":" + std::to_string(ln) + ": time does not increase");
    r.poses.push_back({t, Pose2{x, y, th}});
  }
  if (r.poses.empty()) throw InputError("robot path " + spec + " has no poses");
  return r;
}

std::uint64_t mix(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a * 0x9E3779B97F4A7C15ULL + b + 0x632BE59BD9B4E019ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// The camera's detections (tracking frame) of the counted people `gt` seen from `pose`; see CameraModel.
std::vector<PersonDetection> cameraDetections(const CameraModel& cam, const Pose2& pose, const std::vector<MotObject>& gt,
                                              std::mt19937_64& rng) {
  std::vector<PersonDetection> out;
  if (!(cam.fov > 0.0)) return out;
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const Eigen::Vector2d origin(pose.x, pose.y);
  auto inField = [&](double distance, double bearing) {
    return distance <= cam.range && std::abs(std::remainder(bearing - pose.theta, 2 * M_PI)) <= 0.5 * cam.fov;
  };
  auto detection = [&](double distance, double bearing) {
    PersonDetection d;
    d.position = origin + distance * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
    const double sr = std::max(0.05, cam.range_sigma * distance), sb = std::max(0.01, distance * cam.bearing_sigma);
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(bearing).toRotationMatrix();
    d.covariance = R * Eigen::Vector2d(sr * sr, sb * sb).asDiagonal() * R.transpose();
    d.confidence = 0.9;
    d.legs = 0;
    d.source = 1;
    return d;
  };
  for (const MotObject& g : gt) {
    const Eigen::Vector2d v = g.p - origin;
    const double distance = v.norm(), bearing = std::atan2(v.y(), v.x());
    if (!inField(distance, bearing) || U(rng) >= cam.detection_probability) continue;
    const double noisy_distance = std::max(0.1, distance * (1.0 + cam.range_sigma * N(rng)));
    out.push_back(detection(noisy_distance, bearing + cam.bearing_sigma * N(rng)));
  }
  // Poisson false detections, uniform over the field's area.
  std::poisson_distribution<int> false_count(cam.false_per_scan);
  for (int k = false_count(rng); k > 0; --k) {
    const double distance = cam.range * std::sqrt(U(rng)), bearing = pose.theta + cam.fov * (U(rng) - 0.5);
    out.push_back(detection(distance, bearing));
  }
  return out;
}
// Every score of one tracker's output. The don't-care rule runs once per frame (in CLEAR MOT); the other scorers
// get the hypotheses it kept.
struct Scorers {
  explicit Scorers(double threshold)
      : mot(threshold), hota(2 * threshold, threshold), idf1(threshold), ospa(2 * threshold, 1.0, threshold) {}
  void addFrame(const std::vector<MotObject>& gt, const std::vector<MotObject>& hyp,
                const std::vector<Eigen::Vector2d>& dont_care) {
    mot.addFrame(gt, hyp, dont_care);
    hota.addFrame(gt, mot.lastHypotheses());
    idf1.addFrame(gt, mot.lastHypotheses());
    ospa.addFrame(gt, mot.lastHypotheses());
  }
  void into(BenchRun& run) const {
    run.mot = mot.metrics();
    run.hota = hota.metrics();
    run.id = idf1.metrics();
    run.ospa = ospa.mean();
  }
  ClearMot mot;
  Hota hota;
  IdF1 idf1;
  Ospa ospa;
};

}  // namespace

BenchResult runBench(const BenchParams& params) {
  const bool auto_world = params.world == "auto";
  if (!auto_world && !params.world_geometry)
    throw InputError("world '" + params.world + "': only --world auto without the simulator component (cairn-people "
                     "built with components/sim reads its worlds)");
  // 1 kHz: above any 2D laser's rate (10-50 Hz); a rate of 1e9 replayed forever before.
  if (!(params.scan_rate > 0.0 && params.scan_rate <= 1000.0))
    throw InputError("scan rate (--rate) must be in (0, 1000] Hz, got " + numberText(params.scan_rate));
  if (!(params.start >= 0.0)) throw InputError("start (--start) must be >= 0 s, got " + numberText(params.start));
  if (!(params.duration >= 0.0))
    throw InputError("duration (--duration) must be >= 0 s (0: to the end), got " + numberText(params.duration));
  if (!params.laser_fov_set && (params.laser_beams < 8 || params.laser_beams > 100000))
    throw InputError("laser_beams (--beams) must be in [8, 100000], got " + std::to_string(params.laser_beams));
  if (!(params.trajectory_smoothing >= 0.0 && params.trajectory_smoothing <= 10.0))
    throw InputError("trajectory smoothing (--smooth) must be in [0, 10] s, got " +
                     numberText(params.trajectory_smoothing));
  const CameraModel& cam = params.camera;
  if (!(cam.fov >= 0.0 && cam.fov <= 2 * M_PI) || !(cam.range > 0.0 && cam.range <= 100.0) ||
      !(cam.bearing_sigma >= 0.0 && cam.bearing_sigma < 1.0) || !(cam.range_sigma >= 0.0 && cam.range_sigma < 1.0) ||
      !(cam.detection_probability >= 0.0 && cam.detection_probability <= 1.0) ||
      !(cam.false_per_scan >= 0.0 && cam.false_per_scan <= 100.0))
    throw InputError("camera model out of range (fov [0, 360] deg, range (0, 100] m, bearing sigma [0, 57) deg, "
                     "range sigma [0, 1), detection probability [0, 1], false detections [0, 100] per scan)");
  if (params.oracle_detections && !(params.oracle_sigma > 0.0 && params.oracle_sigma < 10.0))
    throw InputError("oracle sigma must be in (0, 10) m");
  std::vector<IdExchange> exchanges;
  const TrajectorySet traj = [&] {
    TrajectorySet t = loadTrajectories(params.trajectories);
    if (params.fix_id_exchanges) exchanges = fixIdExchanges(t);
    if (params.trajectory_smoothing > 0.0) smoothTrajectories(t, params.trajectory_smoothing);
    return t;
  }();
  if (traj.t_begin + params.start > traj.t_end)
    throw InputError("start (--start) " + numberText(params.start) + " s is beyond the end of " + params.trajectories +
                     " (" + numberText(traj.t_end - traj.t_begin) + " s long)");
  const std::string model_path =
      params.model.empty() ? defaultModelPath(ClassifierKind::kAdaBoost, "arras14") : params.model;
  auto classifier = std::make_shared<const LegClassifier>(LegClassifier::load(model_path));
  const PersonDetector detector(classifier, params.detector);
  MotionEvidence motion(params.motion);

  // Auto world: walls 1.5 m outside the bounding box of all trajectories, robot at the centre.
  const Eigen::Vector2d lo = traj.min - Eigen::Vector2d(1.5, 1.5), hi = traj.max + Eigen::Vector2d(1.5, 1.5);
  // World: the trajectories are moved into it (world = offset (+) data), the robot starts at the world's pose.
  Pose2 offset{};
  if (!auto_world) {
    const Eigen::Vector2d mid = 0.5 * (traj.min + traj.max);
    offset = params.trajectory_offset ? *params.trajectory_offset
                                      : Pose2{params.robot_start.x - mid.x(), params.robot_start.y - mid.y(), 0.0};
  }
  const Eigen::Vector2d center =
      auto_world ? Eigen::Vector2d(0.5 * (lo + hi)) : Eigen::Vector2d(params.robot_start.x, params.robot_start.y);
  Scene walls;
  if (auto_world) {
    walls.addSegment({lo.x(), lo.y()}, {hi.x(), lo.y()}, ObjectClass::kWall);
    walls.addSegment({hi.x(), lo.y()}, {hi.x(), hi.y()}, ObjectClass::kWall);
    walls.addSegment({hi.x(), hi.y()}, {lo.x(), hi.y()}, ObjectClass::kWall);
    walls.addSegment({lo.x(), hi.y()}, {lo.x(), lo.y()}, ObjectClass::kWall);
  }
  RobotPath robot = parseRobotPath(params.robot_path, center, params.robot_route, params.robot_route_speed);
  if (!auto_world && robot.kind == RobotPath::kStatic) robot.heading = params.robot_start.theta;

  LaserModel laser = params.laser;
  if (!params.laser_fov_set) {
    laser.beams = static_cast<std::size_t>(params.laser_beams);
    laser.angle_min = -M_PI;
    laser.angle_increment = 2 * M_PI / params.laser_beams;
  }
  PeopleTracker tracker(params.tracker);
  NearestNeighbourTracker baseline;
  Scorers score(params.match_threshold), score_base(params.match_threshold);
  std::mt19937_64 rng(mix(params.seed, 1));
  std::mt19937_64 oracle_rng(mix(params.seed, 2));  // separate stream: the scans stay those of a normal run
  std::mt19937_64 camera_rng(mix(params.seed, 3));  // likewise

  // Per-person body parameters, seeded by (seed, id).
  std::map<int, WalkerState> walkers;
  std::map<int, Eigen::Vector2d> last_pos;
  for (const auto& [id, v] : traj.people) {
    std::mt19937_64 r(mix(params.seed, static_cast<std::uint64_t>(id) + 1000));
    std::uniform_real_distribution<double> U(0.0, 1.0);
    WalkerState w;
    w.leg_radius = 0.05 + 0.03 * U(r);
    w.hip_half_width = 0.07 + 0.05 * U(r);
    w.gait_phase = 2 * M_PI * U(r);
    walkers[id] = w;
  }

  std::ofstream gt_csv, tr_csv, leg_csv, all_csv, match_csv, dc_csv, robot_csv;
  if (!params.dump_dir.empty()) {
    std::filesystem::create_directories(params.dump_dir);
    gt_csv.open(params.dump_dir + "/groundtruth.csv");
    tr_csv.open(params.dump_dir + "/tracks.csv");
    leg_csv.open(params.dump_dir + "/legs.csv");
    all_csv.open(params.dump_dir + "/tracker_state.csv");
    match_csv.open(params.dump_dir + "/matches.csv");
    dc_csv.open(params.dump_dir + "/dontcare.csv");
    robot_csv.open(params.dump_dir + "/robot.csv");
    if (!gt_csv || !tr_csv || !leg_csv || !all_csv || !match_csv || !dc_csv || !robot_csv) throw InputError("cannot write into dump directory " + params.dump_dir);
    // Round-trip precision: an external scorer reading these files sees the positions the bench scored.
    for (std::ofstream* f : {&gt_csv, &tr_csv, &leg_csv, &all_csv, &match_csv, &dc_csv, &robot_csv})
      f->precision(std::numeric_limits<double>::max_digits10);
    gt_csv << "t,id,x,y\n";
    tr_csv << "t,id,x,y\n";
    leg_csv << "t,x,y,confidence\n";
    all_csv << "t,id,x,y,vx,vy,confirmed,coast_s,visibility\n";
    match_csv << "t,person,track,switched_from\n";
    dc_csv << "t,x,y\n";
    robot_csv << "t,x,y,theta\n";
  }

  BenchResult result;
  result.format = traj.format;
  result.people_in_file = traj.people.size();
  result.id_exchanges_fixed = exchanges;
  const double t0 = traj.t_begin + params.start;
  if (params.static_map) {
    Scene fixed = walls;
    if (params.world_geometry) params.world_geometry(t0, fixed);
    tracker.setStaticMap(std::make_shared<const StaticMap>(rasterize(fixed)));
  }
  const double t_end = params.duration > 0 ? std::min(traj.t_end, t0 + params.duration) : traj.t_end;
  const double dt = 1.0 / params.scan_rate;
  double counted_sum = 0.0;
  using Clock = std::chrono::steady_clock;
  for (std::size_t k = 0;; ++k) {
    const double t = t0 + static_cast<double>(k) * dt;
    if (t > t_end) break;
    Scene scene = walls;
    if (params.world_geometry) params.world_geometry(t, scene);
    std::vector<int> present;
    for (auto& [id, w] : walkers) {
      auto p = traj.positionAt(id, t);
      if (p) *p = offset.transform(*p);
      if (!p) {
        last_pos.erase(id);
        continue;
      }
      const auto prev = last_pos.find(id);
      if (prev != last_pos.end()) {
        const Eigen::Vector2d step = *p - prev->second;
        if (step.norm() > 0.02) w.heading = std::atan2(step.y(), step.x());
        advanceGait(w, step.norm(), dt);
      }
      last_pos[id] = *p;
      w.position = *p;
      addWalker(scene, w, id);
      present.push_back(id);
    }
    const Pose2 pose = robot.at(t, t0);
    const SimScan sim = renderScan(scene, pose, laser, t, rng);

    // Ground truth: people within range and line of sight.
    std::map<int, int> beams_on;
    for (int obj : sim.hit_object)
      if (obj >= 0 && scene.object_person[static_cast<std::size_t>(obj)] >= 0)
        ++beams_on[scene.object_person[static_cast<std::size_t>(obj)]];
    std::vector<MotObject> gt;
    std::vector<Eigen::Vector2d> dont_care;
    for (int id : present) {
      const Eigen::Vector2d p = walkers[id].position;
      const bool in_range = (p - Eigen::Vector2d(pose.x, pose.y)).norm() <= params.sensor_range;
      if (in_range && beams_on[id] >= params.min_visible_beams) gt.push_back({id, p});
      else dont_care.push_back(p);
    }
    counted_sum += static_cast<double>(gt.size());

    const auto c0 = Clock::now();
    const auto legs = detector.detectLegs(sim.scan, &motion, pose, tracker.hasStaticMap());
    motion.add(sim.scan, pose);
    const auto dets = pairLegs(legs, params.detector);
    const auto c1 = Clock::now();
    if (params.oracle_detections) {
      std::vector<PersonDetection> truth;
      std::normal_distribution<double> noise(0.0, params.oracle_sigma);
      for (const MotObject& g : gt) {
        PersonDetection d;
        d.position = g.p + Eigen::Vector2d(noise(oracle_rng), noise(oracle_rng));
        d.covariance = params.oracle_sigma * params.oracle_sigma * Eigen::Matrix2d::Identity();
        d.confidence = 1.0;
        d.legs = 2;
        truth.push_back(d);
      }
      // As another source's detections with no legs, so the tracker still reads the scan for occlusion and free
      // space (its negative information is part of the tracking core).
      tracker.updateLegs(t, {}, pose, params.detector, &sim.scan, truth);
    } else if (params.track_aware_pairing) {
      tracker.updateLegs(t, legs, pose, params.detector, &sim.scan, cameraDetections(cam, pose, gt, camera_rng));
    } else if (cam.fov > 0.0) {
      tracker.updateInFrame(t, fuseDetections({transformDetections(dets, pose), cameraDetections(cam, pose, gt, camera_rng)},
                                              params.tracker.fusion));
    } else {
      tracker.update(t, dets, pose);
    }
    const auto c2 = Clock::now();
    std::vector<PersonDetection> dets_frame = dets;
    for (auto& d : dets_frame) d.position = pose.transform(d.position);
    baseline.update(t, dets_frame);
    const auto c3 = Clock::now();
    const double detect_s = std::chrono::duration<double>(c1 - c0).count();
    result.cairn.process_seconds += detect_s + std::chrono::duration<double>(c2 - c1).count();
    result.baseline.process_seconds += detect_s + std::chrono::duration<double>(c3 - c2).count();

    auto inRange = [&](const Eigen::Vector2d& p) {
      return (p - Eigen::Vector2d(pose.x, pose.y)).norm() <= params.sensor_range;
    };
    std::vector<MotObject> hyp, hyp_base;
    for (const Track& tr : tracker.outputTracks())
      if (inRange(tr.position())) hyp.push_back({tr.id, tr.position()});
    for (const MotObject& o : baseline.confirmed())
      if (inRange(o.p)) hyp_base.push_back(o);
    score.addFrame(gt, hyp, dont_care);
    score_base.addFrame(gt, hyp_base, dont_care);
    if (gt_csv.is_open()) {
      for (const auto& g : gt) gt_csv << t << ',' << g.id << ',' << g.p.x() << ',' << g.p.y() << '\n';
      for (const auto& d : dont_care) dc_csv << t << ',' << d.x() << ',' << d.y() << '\n';
      robot_csv << t << ',' << pose.x << ',' << pose.y << ',' << pose.theta << '\n';
      for (const auto& h : hyp) tr_csv << t << ',' << h.id << ',' << h.p.x() << ',' << h.p.y() << '\n';
      for (const auto& c : score.mot.lastFrame()) match_csv << t << ',' << c.gt << ',' << c.hyp << ',' << c.switched_from << '\n';
      for (const Track& tr : tracker.tracks())
        all_csv << t << ',' << tr.id << ',' << tr.state(0) << ',' << tr.state(1) << ',' << tr.state(2) << ','
                << tr.state(3) << ',' << tr.confirmed << ',' << tr.stamp - tr.last_update << ','
                << static_cast<int>(tr.visibility) << '\n';
      for (const auto& l : legs) {
        const Eigen::Vector2d q = pose.transform(l.position);
        leg_csv << t << ',' << q.x() << ',' << q.y() << ',' << l.confidence << '\n';
      }
    }
    ++result.scans;
  }
  result.duration = static_cast<double>(result.scans) * dt;
  result.mean_people_counted = result.scans ? counted_sum / static_cast<double>(result.scans) : 0.0;
  score.into(result.cairn);
  score_base.into(result.baseline);
  return result;
}

std::string benchJson(const BenchParams& p, const BenchResult& r) {
  auto run = [&](const BenchRun& b) {
    char buf[768];
    std::snprintf(buf, sizeof buf,
                  "{\"mota\": %.4f, \"motp\": %.4f, \"id_switches\": %zu, \"id_switches_per_100_tracks\": %.3f, "
                  "\"fp\": %zu, \"fn\": %zu, \"matches\": %zu, \"gt\": %zu, \"gt_tracks\": %zu, \"id_transfers\": %zu, "
                  "\"hota\": %.4f, \"deta\": %.4f, \"assa\": %.4f, \"loca\": %.4f, \"hota_at_0_5\": %.4f, "
                  "\"deta_at_0_5\": %.4f, \"assa_at_0_5\": %.4f, \"idf1\": %.4f, \"idp\": %.4f, \"idr\": %.4f, "
                  "\"ospa_m\": %.4f, "
                  "\"scans_per_second\": %.1f}",
                  b.mot.mota(), b.mot.motp(), b.mot.id_switches, b.mot.idSwitchesPer100Tracks(), b.mot.fp, b.mot.fn,
                  b.mot.matches, b.mot.gt, b.mot.gt_tracks, b.mot.id_transfers, b.hota.hota, b.hota.deta, b.hota.assa, b.hota.loca,
                  b.hota.hota_alpha[HotaMetrics::kHalf], b.hota.deta_alpha[HotaMetrics::kHalf],
                  b.hota.assa_alpha[HotaMetrics::kHalf], b.id.idf1, b.id.idp, b.id.idr, b.ospa,
                  b.scansPerSecond(r.scans));
    return std::string(buf);
  };
  std::ostringstream o;
  o << "{\"trajectories\": \"" << p.trajectories << "\", \"format\": \"" << r.format << "\", \"world\": \"" << p.world
    << "\", \"robot\": \"" << (p.robot_path.empty() ? "static" : p.robot_path) << "\", \"seed\": " << p.seed
    << ", \"association\": \"" << toString(p.tracker.association) << "\", \"scan_rate\": " << p.scan_rate
    << ", \"scans\": " << r.scans << ", \"duration_s\": " << r.duration << ", \"people_in_file\": " << r.people_in_file
    << ", \"mean_people_counted\": " << r.mean_people_counted << ", \"match_threshold_m\": " << p.match_threshold
    << ", \"sensor_range_m\": " << p.sensor_range;
  if (!p.laser_fov_set) o << ", \"laser_beams\": " << p.laser_beams;
  o << ", \"trajectory_smoothing_s\": " << p.trajectory_smoothing;
  if (p.fix_id_exchanges) {
    o << ", \"id_exchanges_fixed\": [";
    for (std::size_t i = 0; i < r.id_exchanges_fixed.size(); ++i) {
      const IdExchange& e = r.id_exchanges_fixed[i];
      o << (i ? ", " : "") << "{\"a\": " << e.a << ", \"b\": " << e.b << ", \"after_s\": " << e.after << "}";
    }
    o << "]";
  }
  o << ", \"motion_window_s\": " << p.motion.window << ", \"motion_memory_s\": " << p.motion.memory;
  o << ", \"static_map\": " << (p.static_map ? "true" : "false");
  if (p.camera.fov > 0.0)
    o << ", \"camera\": {\"fov_deg\": " << p.camera.fov * 180.0 / M_PI << ", \"range_m\": " << p.camera.range
      << ", \"bearing_sigma_deg\": " << p.camera.bearing_sigma * 180.0 / M_PI << ", \"range_sigma\": "
      << p.camera.range_sigma << ", \"detection_probability\": " << p.camera.detection_probability
      << ", \"false_per_scan\": " << p.camera.false_per_scan << "}";
  o << ", \"cairn\": " << run(r.cairn)
    << ", \"baseline\": " << run(r.baseline) << ", \"baseline_name\": \"greedy nearest neighbour, no motion model\"}";
  return o.str();
}

}  // namespace cairn::people_tracking
