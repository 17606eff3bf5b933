// cairn_people_tracking::PeopleTracker — the runtime adapter of the people_tracking core: LaserScan (+ Odometry
// for robot-motion compensation) in; person detections, tracks, guide state and a person-masked scan out.
// Thin: message conversion, parameter plumbing and calls into the core (detector.hpp, tracker.hpp, guide.hpp,
// masking.hpp). Bad input (malformed scans, time going backwards, missing odometry) is logged and skipped.
#include <dlfcn.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "cairn/component.hpp"
#include "cairn/data_files.hpp"
#include "cairn/msg_conversions.hpp"
#include "cairn/people_tracking/classifier.hpp"
#include "cairn/people_tracking/detector.hpp"
#include "cairn/people_tracking/guide.hpp"
#include "cairn/people_tracking/masking.hpp"
#include "cairn/people_tracking/param_ranges.hpp"
#include "cairn/people_tracking/static_map.hpp"
#include "cairn/people_tracking/tracker.hpp"
#include "cairn/tf.hpp"
#include "cairn_people_msgs/msg/GuideState.hpp"
#include "cairn_people_msgs/msg/PersonDetections.hpp"
#include "cairn_people_msgs/msg/TrackedPersons.hpp"
#include "cairn_people_msgs/srv/Follow.hpp"
#include "nav_msgs/msg/OccupancyGrid.hpp"
#include "nav_msgs/msg/Odometry.hpp"
#include "sensor_msgs/msg/LaserScan.hpp"

namespace cairn_people_tracking {

namespace pt = cairn::people_tracking;
namespace pmsg = cairn_people_msgs::msg;
namespace psrv = cairn_people_msgs::srv;

namespace {

constexpr const char* kDefaultModel = "leg_adaboost_arras14.yml";  // the model `cairn people bench` uses

using cairn::time_from_seconds;
using cairn::to_seconds;
using cairn::yaw_of;

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// The planar part of a TF transform (translation x, y and the yaw of its x axis).
pt::Pose2 planar(const cairn::RigidTransform& tf) {
  const Eigen::Vector3d x = tf.q * Eigen::Vector3d::UnitX();
  return pt::Pose2{tf.t.x(), tf.t.y(), std::atan2(x.y(), x.x())};
}

// Directory of this component library (for models installed next to it: <prefix>/lib/cairn_components/x.so).
std::filesystem::path libraryDir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&libraryDir), &info) == 0 || info.dli_fname == nullptr) return {};
  std::error_code ec;
  auto p = std::filesystem::weakly_canonical(std::filesystem::path(info.dli_fname), ec);
  return ec ? std::filesystem::path(info.dli_fname).parent_path() : p.parent_path();
}

// Model file: "" -> the shipped default. A relative path is tried against the working directory, the installed
// share/cairn_people_tracking/models of this library's prefix and of $CMAKE_PREFIX_PATH/$COLCON_PREFIX_PATH, and
// the package's source models/ directory (build tree). Throws std::invalid_argument naming what was tried.
std::string resolveModelPath(const std::string& param) {
  namespace fs = std::filesystem;
  const std::string name = param.empty() ? kDefaultModel : param;
  const fs::path p(name);
  if (p.is_absolute()) {
    if (!fs::exists(p)) throw std::invalid_argument("model_file: '" + name + "' does not exist");
    return name;
  }
  std::vector<fs::path> candidates;
  if (!param.empty()) candidates.push_back(fs::current_path() / p);
  const fs::path lib = libraryDir();
  if (!lib.empty()) candidates.push_back(lib.parent_path().parent_path() / "share/cairn_people_tracking/models" / p);
  for (const auto& dir : cairn::prefix_paths("share/cairn_people_tracking/models")) candidates.push_back(dir / p);
#ifdef CAIRN_PEOPLE_MODEL_DIR
  candidates.push_back(fs::path(CAIRN_PEOPLE_MODEL_DIR) / p);
#endif
  return cairn::first_existing_file(candidates, "model_file: '" + name + "'");
}

}  // namespace

class PeopleTracker : public cairn::Node {
 public:
  explicit PeopleTracker(const cairn::NodeOptions& o) : cairn::Node(o) {
    using D = cairn::ParameterDescriptor;
    const std::string model_param = declare_parameter<std::string>(
        "model_file", "", D{"leg classifier model (cairn people train); empty: the shipped " + std::string(kDefaultModel) +
                               "; relative paths also searched in share/cairn_people_tracking/models", {}, {}, true});
    use_odom_ = declare_parameter<bool>("use_odom", true, D{"compensate robot motion with `odom` (tracks in its frame); false: tracks in the laser frame", {}, {}, true});
    odom_tolerance_ = declare_parameter<double>("odom_tolerance", 0.2, D{"s a scan may be newer/older than the odometry buffer (extrapolated with the twist)", 0.0, 2.0, true});
    odom_queue_ = static_cast<int>(declare_parameter<int64_t>("odom_queue", 10, D{"scans that may wait for odometry lagging them by more than odom_tolerance (0: ignored at once)", 0.0, 1000.0, true}));
    base_frame_ = declare_parameter<std::string>("base_frame", "base_link", D{"robot frame of the odometry (child frame); the laser mount is looked up as TF base_frame <- scan frame_id", {}, {}, true});
    tf_timeout_ = declare_parameter<double>("tf_timeout", 1.0, D{"s of scans to wait for the base_frame <- laser TF before using sensor_x/y/yaw", 0.0, 60.0, true});
    mount_.x = declare_parameter<double>("sensor_x", 0.0, D{"fallback laser position in the base frame when no TF arrives within tf_timeout, m", -10.0, 10.0, true});
    mount_.y = declare_parameter<double>("sensor_y", 0.0, D{"fallback laser position in the base frame, m", -10.0, 10.0, true});
    mount_.theta = declare_parameter<double>("sensor_yaw", 0.0, D{"fallback laser yaw in the base frame, rad", -M_PI, M_PI, true});

    // Detector (segmentation.hpp, detector.hpp).
    pt::DetectorParams dp;
    auto& sp = dp.segmentation;
    sp.jump_base = declareRanged<double>("segmentation.jump_base", sp.jump_base, "m, fixed part of the jump threshold");
    sp.jump_beam_factor = declareRanged<double>("segmentation.jump_beam_factor", sp.jump_beam_factor, "multiples of the beam spacing r*dtheta");
    sp.max_gap_beams = static_cast<int>(declareRanged<int64_t>("segmentation.max_gap_beams", sp.max_gap_beams, "invalid beams tolerated inside a cluster"));
    sp.min_points = static_cast<std::size_t>(declareRanged<int64_t>("segmentation.min_points", static_cast<int64_t>(sp.min_points), "smallest cluster"));
    sp.max_points = static_cast<std::size_t>(declareRanged<int64_t>("segmentation.max_points", static_cast<int64_t>(sp.max_points), "largest cluster"));
    sp.jump_cap = declareRanged<double>("segmentation.jump_cap", sp.jump_cap, "m, neighbour jump when there is no neighbour");
    declareRuntimeField("detector.min_leg_confidence", dp, detector_params_, &pt::DetectorParams::min_leg_confidence,
                        "classifier score to accept a leg");
    declareRuntimeField("detector.track_leg_confidence", dp, detector_params_, &pt::DetectorParams::track_leg_confidence,
                        "weaker legs that may only update existing tracks");
    declareRuntimeField("detector.track_leg_confidence_with_map", dp, detector_params_,
                        &pt::DetectorParams::track_leg_confidence_with_map,
                        "replaces detector.track_leg_confidence while the static map is attached");
    declareRuntimeField("detector.moving_fraction", dp, detector_params_, &pt::DetectorParams::moving_fraction,
                        "share of a cluster's points an earlier scan saw as free space for it to count as moving");
    declareRuntimeField("detector.moving_track_leg_confidence", dp, detector_params_, &pt::DetectorParams::moving_track_leg_confidence,
                        "score a moving cluster needs to update existing tracks");
    declareRuntimeField("detector.moving_min_leg_confidence", dp, detector_params_, &pt::DetectorParams::moving_min_leg_confidence,
                        "score a moving cluster needs to form persons and start tracks");
    declareRuntimeField("detector.crossed_track_leg_confidence", dp, detector_params_,
                        &pt::DetectorParams::crossed_track_leg_confidence,
                        "score a cluster where the beams went through earlier (not static background) needs to update tracks");
    // Motion evidence (motion_evidence.hpp): the scans of the last motion.window seconds.
    pt::MotionEvidenceParams mp;
    mp.window = declareRanged<double>("motion.window", mp.window, "s of earlier scans consulted for motion evidence (0 = off)");
    mp.min_age = declareRanged<double>("motion.min_age", mp.min_age, "s, earlier scans younger than this are not consulted");
    mp.margin = declareRanged<double>("motion.margin", mp.margin, "m, an earlier beam must end this far behind a point to see it free");
    mp.slope_factor = declareRanged<double>("motion.slope_factor", mp.slope_factor,
                                            "a grazing surface's range step per beam, extrapolated to the point's bearing (0 = off)");
    mp.min_free_scans = static_cast<std::size_t>(declareRanged<int64_t>("motion.min_free_scans", static_cast<int64_t>(mp.min_free_scans),
                                                                        "earlier scans that must see a point free"));
    // Free-space memory (FreeSpaceMemory): where the beams went through, in a grid around the robot.
    mp.memory = declareRanged<double>("motion.memory", mp.memory, "s a place the beams went through is remembered as free (0 = off)");
    mp.memory_resolution = declareRanged<double>("motion.memory_resolution", mp.memory_resolution, "m, cell of the free-space memory");
    mp.memory_size = declareRanged<double>("motion.memory_size", mp.memory_size, "m, side of the free-space memory's grid around the robot");
    mp.memory_surface_gap = declareRanged<double>("motion.memory_surface_gap", mp.memory_surface_gap,
                                                  "m, consecutive returns closer than this are one surface (not free between them)");
    declareRuntimeField("detector.small_cluster_min_range", dp, detector_params_, &pt::DetectorParams::small_cluster_min_range,
                        "m, clusters of 1-2 points closer than this are dropped");
    declareRuntimeField("detector.max_range", dp, detector_params_, &pt::DetectorParams::max_range,
                        "m, clusters beyond are ignored");
    declareRuntimeField("detector.max_leg_width", dp, detector_params_, &pt::DetectorParams::max_leg_width,
                        "m, wider clusters are not legs");
    declareRuntimeField("detector.split_min_width", dp, detector_params_, &pt::DetectorParams::split_min_width,
                        "m, clusters this wide may be split into two legs at a step (above max_leg_width: off)");
    declareRuntimeField("detector.split_gap_ratio", dp, detector_params_, &pt::DetectorParams::split_gap_ratio,
                        "a split step is this many times the cluster's median step between returns");
    declareRuntimeField("detector.split_min_gap_beams", dp, detector_params_, &pt::DetectorParams::split_min_gap_beams,
                        "a split step is at least this many beam spacings");
    declareRuntimeField("detector.leg_center_offset", dp, detector_params_, &pt::DetectorParams::leg_center_offset,
                        "m, leg centre behind the visible surface");
    declareRuntimeField("detector.max_leg_pair_distance", dp, detector_params_, &pt::DetectorParams::max_leg_pair_distance,
                        "m, legs closer than this are paired");
    declareRuntimeField("detector.single_leg_min_confidence", dp, detector_params_, &pt::DetectorParams::single_leg_min_confidence,
                        "score an unpaired cluster needs to become a person");
    declareRuntimeField("detector.sigma_pair", dp, detector_params_, &pt::DetectorParams::sigma_pair,
                        "m, position std of a paired-leg person");
    declareRuntimeField("detector.sigma_single", dp, detector_params_, &pt::DetectorParams::sigma_single,
                        "m, position std of a single-cluster person");

    // Tracker (tracker.hpp; Stüde §2.1.3).
    pt::TrackerParams tp;
    const std::string assoc = declare_parameter<std::string>("tracker.association", "gnn", D{"gnn | jpda", {}, {}, true});
    try {
      tp.association = pt::associationFromString(assoc);
    } catch (const pt::InputError&) {
      throw std::invalid_argument("parameter 'tracker.association' must be gnn or jpda, got '" + assoc + "'");
    }
    tp.process_noise = declareRanged<double>("tracker.process_noise", tp.process_noise, "m^2/s^3, CV white-noise acceleration density");
    tp.maneuver_process_noise = declareRanged<double>("tracker.maneuver_process_noise", tp.maneuver_process_noise, "m^2/s^3, IMM manoeuvre mode (0 = one walking mode)");
    tp.maneuver_rate = declareRanged<double>("tracker.maneuver_rate", tp.maneuver_rate, "1/s, IMM walking -> manoeuvre switching rate");
    tp.maneuver_end_rate = declareRanged<double>("tracker.maneuver_end_rate", tp.maneuver_end_rate, "1/s, IMM manoeuvre -> walking switching rate");
    tp.maneuver_gate_sigma = declareRanged<double>("tracker.maneuver_gate_sigma", tp.maneuver_gate_sigma, "m, maneuver gate: S + sigma^2 I for a confirmed track the gate left without a detection (0 = off)");
    tp.maneuver_gate_time = declareRanged<double>("tracker.maneuver_gate_time", tp.maneuver_gate_time, "s, maneuver gate: velocity variance added = (sigma / time)^2");
    tp.adaptive_nis_threshold = declareRanged<double>("tracker.adaptive_nis_threshold", tp.adaptive_nis_threshold, "smoothed NIS above which a track's process noise is raised (0 = off; one mode only)");
    tp.adaptive_noise_gain = declareRanged<double>("tracker.adaptive_noise_gain", tp.adaptive_noise_gain, "process noise factor while the smoothed NIS is above the threshold");
    tp.adaptive_nis_smoothing = declareRanged<double>("tracker.adaptive_nis_smoothing", tp.adaptive_nis_smoothing, "weight of the newest NIS in the smoothed value");
    tp.initial_velocity_sigma = declareRanged<double>("tracker.initial_velocity_sigma", tp.initial_velocity_sigma, "m/s, velocity std of a new track");
    tp.gate_chi2 = declareRanged<double>("tracker.gate_chi2", tp.gate_chi2, "chi-square gate (2 dof)");
    tp.confirm_hits = static_cast<int>(declareRanged<int64_t>("tracker.confirm_hits", tp.confirm_hits, "associated scans until confirmed"));
    tp.confirm_score = declareRanged<double>("tracker.confirm_score", tp.confirm_score, "track score (log-likelihood ratio) until confirmed; 0 = hits only");
    tp.tentative_timeout = declareRanged<double>("tracker.tentative_timeout", tp.tentative_timeout, "s without update deletes a tentative track");
    tp.delete_timeout = declareRanged<double>("tracker.delete_timeout", tp.delete_timeout, "s without update deletes a confirmed track");
    tp.max_position_sigma = declareRanged<double>("tracker.max_position_sigma", tp.max_position_sigma, "m, deletion when the position std grows beyond");
    tp.min_init_distance = declareRanged<double>("tracker.min_init_distance", tp.min_init_distance, "m, no new track this close to a confirmed one");
    tp.publish_coast_time = declareRanged<double>("tracker.publish_coast_time", tp.publish_coast_time, "s, coasting confirmed tracks are published this long");
    tp.max_dt = declareRanged<double>("tracker.max_dt", tp.max_dt, "s, larger forward time jumps reset the tracker");
    tp.detection_probability = declareRanged<double>("tracker.detection_probability", tp.detection_probability, "JPDA P_D");
    tp.clutter_density = declareRanged<double>("tracker.clutter_density", tp.clutter_density, "JPDA false detections per m^2");
    tp.jpda_max_events = static_cast<int>(declareRanged<int64_t>("tracker.jpda_max_events", tp.jpda_max_events, "larger JPDA gating clusters fall back to GNN"));
    tp.min_detection_confidence = declareRanged<double>("tracker.min_detection_confidence", tp.min_detection_confidence, "detections below are not used");
    tp.confidence_gain = declareRanged<double>("tracker.confidence_gain", tp.confidence_gain, "track confidence moving-average gain");
    tp.leg_spread_sigma = declareRanged<double>("tracker.leg_spread_sigma", tp.leg_spread_sigma, "m, std of a leg around the body centre (along the walking direction)");
    tp.leg_spread_lateral_sigma = declareRanged<double>("tracker.leg_spread_lateral_sigma", tp.leg_spread_lateral_sigma, "m, leg spread across the walking direction");
    tp.leg_spread_min_speed = declareRanged<double>("tracker.leg_spread_min_speed", tp.leg_spread_min_speed, "m/s, slower tracks use an isotropic leg spread");
    tp.leg_gate_chi2 = declareRanged<double>("tracker.leg_gate_chi2", tp.leg_gate_chi2, "chi-square gate (2 dof) of a leg around a track");
    tp.confidence_cost = declareRanged<double>("tracker.confidence_cost", tp.confidence_cost, "leg cost added per unit of missing track confidence (0 = off)");
    tp.reid_window = declareRanged<double>("tracker.reid_window", tp.reid_window, "s, deleted tracks can give their id to a new track this long (0: off)");
    tp.reid_gate_chi2 = declareRanged<double>("tracker.reid_gate_chi2", tp.reid_gate_chi2, "chi-square gate (2 dof) of re-identification");
    tp.reid_max_distance = declareRanged<double>("tracker.reid_max_distance", tp.reid_max_distance, "m, re-identification also needs the new track this close to the deleted track's prediction");
    tp.visibility_radius = declareRanged<double>("tracker.visibility_radius", tp.visibility_radius, "m, beams this close to a track decide occluded / free space / missed");
    tp.occluded_coast_time = declareRanged<double>("tracker.occluded_coast_time", tp.occluded_coast_time, "s, occluded confirmed tracks are published this long");
    tp.occluded_delete_timeout = declareRanged<double>("tracker.occluded_delete_timeout", tp.occluded_delete_timeout, "s without update deletes a track occluded since its last update");
    tp.free_space_delete_scans = static_cast<int>(declareRanged<int64_t>("tracker.free_space_delete_scans", tp.free_space_delete_scans, "consecutive scans with beams through a track delete it"));
    tp.standing_time = declareRanged<double>("tracker.standing_time", tp.standing_time, "s below standing_speed after which a track that gets nothing is predicted in place (0 = off)");
    tp.standing_speed = declareRanged<double>("tracker.standing_speed", tp.standing_speed, "m/s, a track slower than this after every update for standing_time is standing");
    tp.standing_position_noise = declareRanged<double>("tracker.standing_position_noise", tp.standing_position_noise, "m^2/s, position variance growth of a standing track while it gets nothing");
    tp.split_scans = static_cast<int>(declareRanged<int64_t>("tracker.split_scans", tp.split_scans, "scans with four legs in a track's gate before it splits (0 = never)"));
    tp.joint_pairs_max_nodes = static_cast<int>(declareRanged<int64_t>("tracker.joint_pairs_max_nodes", tp.joint_pairs_max_nodes, "search nodes per gating cluster for the joint leg pairing (0 = per-leg Hungarian)"));
    tp.single_leg_stride_sigma = declareRanged<double>("tracker.single_leg_stride_sigma", tp.single_leg_stride_sigma, "m, single-leg update std along the walking direction (0 = off)");
    // Static map (static_map.hpp): legs on its occupied cells are dropped (wall ends, furniture seen edge-on).
    static_map_topic_ = declare_parameter<std::string>("static_map.topic", "", D{"OccupancyGrid (latched) whose occupied cells are not people, e.g. the SLAM map; empty = off", {}, {}, true});
    tp.static_map_margin = declareRanged<double>("static_map.margin", tp.static_map_margin, "m, legs this close to an occupied cell are dropped");
    static_map_threshold_ = static_cast<int>(declare_parameter<int64_t>("static_map.occupied_threshold", 65, D{"cell value (0-100) from which a cell is occupied", 1.0, 100.0, true}));
    // Other detection sources (Stüde §2.1.3; PeopleTracker::updateLegs `others`).
    fusion_topic_ = declare_parameter<std::string>("fusion.topic", "", D{"PersonDetections of another source (a camera detector, a second laser) fused with the legs; empty = off", {}, {}, true});
    fusion_max_age_ = declare_parameter<double>("fusion.max_age", fusion_max_age_, D{"s, a scan uses the message nearest its stamp within this time, once", 0.0, 5.0, true});
    fusion_wait_ = declare_parameter<double>("fusion.wait", fusion_wait_, D{"s (scan time), how long a scan waits for messages of fusion.topic lagging behind it (0: never waits)", 0.0, 5.0, true});
    tp.fusion.max_pair_distance = declareRanged<double>("fusion.max_pair_distance", tp.fusion.max_pair_distance, "m, farther detections are not fused with a person from legs");
    tp.fusion.gate_chi2 = declareRanged<double>("fusion.gate_chi2", tp.fusion.gate_chi2, "Mahalanobis gate of a pair (0: Euclidean nearest pairs, as in the thesis)");

    // Guide (guide.hpp; Yuan §2.2.1).
    pt::GuideParams gp;
    declareRuntimeField("guide.field_radius", gp, guide_params_, &pt::GuideParams::field_radius,
                        "m, radius of the field in front of the robot (Yuan: 8 m)");
    gp.field_half_angle = M_PI / 180.0 * declareRuntime<double>("guide.field_half_angle_deg", 90.0, rangedDescriptor("guide.field_half_angle_deg", "deg, half opening of the field (Yuan: semicircle)"),
        [this](double deg) { guide_params_.field_half_angle = M_PI / 180.0 * deg; });
    declareRuntimeField("guide.select_max_distance", gp, guide_params_, &pt::GuideParams::select_max_distance,
                        "m, follow(closest) considers people this close");
    declareRuntimeField("guide.lost_timeout", gp, guide_params_, &pt::GuideParams::lost_timeout,
                        "s unmatched until Person Lost");
    declareRuntimeField("guide.auto_reacquire", gp, guide_params_, &pt::GuideParams::auto_reacquire,
                        "re-acquire a track appearing near the lost guide");
    declareRuntimeField("guide.reacquire_radius", gp, guide_params_, &pt::GuideParams::reacquire_radius,
                        "m around the last guide position");
    declareRuntimeField("guide.reacquire_window", gp, guide_params_, &pt::GuideParams::reacquire_window,
                        "s before Person Lost falls back to Search");

    // Masking (masking.hpp; Yuan §3.2.1).
    mask_mode_ = declareRuntime<std::string>("mask.people", "all", D{"whom scan_filtered hides: all (published tracks) | guide (Yuan §3.2.1) | none", {}, {}},
        [this](const std::string& x) { mask_mode_ = x; });
    if (auto bad = checkChoice("mask.people", mask_mode_)) throw std::invalid_argument(*bad);
    declareRuntimeField("mask.leg_radius", mask_, mask_, &pt::MaskParams::leg_radius,
                        "m, added to half the leg separation");
    declareRuntimeField("mask.margin", mask_, mask_, &pt::MaskParams::margin,
                        "m, safety margin of r_P");
    declareRuntimeField("mask.default_radius", mask_, mask_, &pt::MaskParams::default_radius,
                        "m, r_P when the leg separation is unknown");
    declareRuntimeField("mask.min_radius", mask_, mask_, &pt::MaskParams::min_radius,
                        "m, smallest r_P");
    const std::string mask_kind = declareRuntime<std::string>("mask.mode", "inside", D{"inside: only returns inside the circle | tangents: every beam between the tangents (Yuan §3.2.1)", {}, {}},
        [this](const std::string& x) { mask_kind_ = pt::parseMaskMode(x, "parameter 'mask.mode'"); });
    if (auto bad = checkChoice("mask.mode", mask_kind)) throw std::invalid_argument(*bad);
    mask_kind_ = pt::parseMaskMode(mask_kind, "parameter 'mask.mode'");

    // The model is loaded in a dry run too, so `cairn launch --check` reports a missing or corrupt model file.
    const std::string model_path = resolveModelPath(model_param);
    try {
      classifier_ = std::make_shared<const pt::LegClassifier>(pt::LegClassifier::load(model_path));
    } catch (const pt::InputError& e) {
      throw std::invalid_argument(std::string("model_file: ") + e.what());
    }
    detector_ = std::make_unique<pt::PersonDetector>(classifier_, dp);
    motion_ = std::make_unique<pt::MotionEvidence>(mp);
    tracker_ = std::make_unique<pt::PeopleTracker>(tp);
    if (use_odom_) {
      tf_buffer_ = std::make_shared<cairn::TransformBuffer>(30.0);
      tf_listener_ = std::make_unique<cairn::TransformListener>(*this, tf_buffer_);
    }
    guide_ = std::make_unique<pt::GuideTracker>(gp);

    det_pub_ = create_publisher<pmsg::PersonDetections>("people/detections", cairn::QoS{});
    track_pub_ = create_publisher<pmsg::TrackedPersons>("people/tracks", cairn::QoS{});
    guide_pub_ = create_publisher<pmsg::GuideState>("people/guide", cairn::QoS{});
    masked_pub_ = create_publisher<sensor_msgs::msg::LaserScan>("scan_filtered", cairn::QoS::sensor_data());
    scan_sub_ = create_subscription<sensor_msgs::msg::LaserScan>(
        "scan", cairn::QoS::sensor_data(), [this](const sensor_msgs::msg::LaserScan& m) { onScan(m); });
    if (!static_map_topic_.empty())
      map_sub_ = create_subscription<nav_msgs::msg::OccupancyGrid>(
          static_map_topic_, cairn::QoS::latched(), [this](const nav_msgs::msg::OccupancyGrid& m) { onMap(m); });
    if (use_odom_)
      odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
          "odom", cairn::QoS{}, [this](const nav_msgs::msg::Odometry& m) { onOdom(m); });
    if (!fusion_topic_.empty())
      other_sub_ = create_subscription<pmsg::PersonDetections>(
          fusion_topic_, cairn::QoS{}, [this](const pmsg::PersonDetections& m) { onOtherDetections(m); });
    follow_srv_ = create_service<psrv::Follow_Request, psrv::Follow_Response>(
        "people/follow", [this](const psrv::Follow_Request& rq, psrv::Follow_Response& rs) { onFollow(rq, rs); });
    // Run-time changes (`cairn param set`) of the detector.*, guide.* and mask.* parameters: checked here, applied
    // before the next scan (on the executor thread that processes scans, so nothing changes during one).
    on_parameter_change([this](const std::string& name, const cairn::ParameterValue& v) -> std::optional<std::string> {
      if (!runtime_setters_.count(name)) return std::nullopt;
      if (const auto* text = std::get_if<std::string>(&v))
        if (auto bad = checkChoice(name, *text)) return bad;
      std::lock_guard l(pending_mu_);
      pending_[name] = v;
      return std::nullopt;
    });
    CAIRN_INFO(logger(), "model " << model_path << ", association " << assoc << ", "
                                  << (use_odom_ ? "tracking in the odometry frame" : "tracking in the laser frame"));
  }

 private:
  // Declares a parameter that may change at run time; `apply` sets it on the staged detector/guide parameters or
  // the mask settings when applyPendingParameters() runs.
  template <class T, class F>
  T declareRuntime(const std::string& name, const T& def, cairn::ParameterDescriptor desc, F apply) {
    desc.read_only = false;
    const T value = declare_parameter<T>(name, def, desc);
    runtime_setters_[name] = [name, apply](const cairn::ParameterValue& v) { apply(cairn::parameter_as<T>(v, name)); };
    return value;
  }
  // The common case: a field of a parameter struct. Declared with `initial.*field` as default (the value goes back
  // there); a run-time change sets `staged.*field`. Numbers take their range from the core's table.
  template <class S, class T>
  void declareRuntimeField(const std::string& name, S& initial, S& staged, T S::*field, const std::string& desc) {
    const cairn::ParameterDescriptor d =
        std::is_same_v<T, bool> ? cairn::ParameterDescriptor{desc, {}, {}} : rangedDescriptor(name, desc);
    initial.*field = declareRuntime<T>(name, initial.*field, d, [&staged, field](const T& x) { staged.*field = x; });
  }
  // A construction-time parameter whose range is in the core's table (param_ranges.hpp).
  template <class T>
  T declareRanged(const std::string& name, const T& def, const std::string& desc) {
    cairn::ParameterDescriptor d = rangedDescriptor(name, desc);
    d.read_only = true;
    return declare_parameter<T>(name, def, d);
  }
  static cairn::ParameterDescriptor rangedDescriptor(const std::string& name, const std::string& desc) {
    const pt::ParamRange r = pt::paramRange(name);
    return cairn::ParameterDescriptor{desc, r.lo, r.hi};
  }

  // The string parameters' choices; the reason when `value` is not one of them.
  static std::optional<std::string> checkChoice(const std::string& name, const std::string& value) {
    if (name == "mask.people" && value != "all" && value != "guide" && value != "none")
      return "parameter 'mask.people' must be all, guide or none, got '" + value + "'";
    if (name == "mask.mode") {
      try {
        pt::parseMaskMode(value, "parameter 'mask.mode'");
      } catch (const pt::InputError& e) {
        return std::string(e.what());
      }
    }
    return std::nullopt;
  }

  // Parameter changes since the last scan, in the order of their names.
  void applyPendingParameters() {
    std::map<std::string, cairn::ParameterValue> pending;
    {
      std::lock_guard l(pending_mu_);
      pending.swap(pending_);
    }
    if (pending.empty()) return;
    detector_params_ = detector_->params();
    guide_params_ = guide_->params();
    bool detector_changed = false;
    for (const auto& [name, value] : pending) {
      runtime_setters_.at(name)(value);
      detector_changed |= name.rfind("detector.", 0) == 0;
      CAIRN_INFO(logger(), "parameter " << name << " := " << cairn::to_string(value) << " from this scan on");
    }
    if (detector_changed) detector_ = std::make_unique<pt::PersonDetector>(classifier_, detector_params_);
    guide_->setParams(guide_params_);
  }

  struct OtherDetections {
    double stamp;
    std::string frame;
    std::vector<pt::PersonDetection> detections;
  };
  struct OdomSample {
    double stamp;
    pt::Pose2 pose;
    double vx, vy, wz;  // body-frame twist
  };

  // Laser mount from TF (base_frame <- scan frame, latest); while it is missing, scans are skipped for
  // tf_timeout seconds (scan time) and then the sensor_x/y/yaw parameters are used (logged once). A TF that
  // arrives later still replaces the parameters.
  bool resolveMount(const std::string& laser_frame, double stamp) {
    if (mount_from_tf_) return true;
    if (laser_frame.empty() || laser_frame == base_frame_) {
      if (laser_frame == base_frame_) {
        mount_ = pt::Pose2{};
        mount_from_tf_ = true;
      }
      return true;
    }
    try {
      mount_ = planar(tf_buffer_->lookup(base_frame_, laser_frame, cairn::Time{0}));
      mount_from_tf_ = true;
      CAIRN_INFO(logger(), "laser mount from TF " << base_frame_ << " <- " << laser_frame << ": (" << mount_.x << ", "
                                                  << mount_.y << ", " << mount_.theta << ")");
      return true;
    } catch (const cairn::TransformError& e) {
      if (!first_scan_stamp_) first_scan_stamp_ = stamp;
      if (stamp - *first_scan_stamp_ < tf_timeout_) return false;
      if (!mount_fallback_logged_)
        CAIRN_WARN(logger(), "no TF " << base_frame_ << " <- " << laser_frame << " after " << tf_timeout_ << " s ("
                                      << e.what() << "): using sensor_x/y/yaw (" << mount_.x << ", " << mount_.y
                                      << ", " << mount_.theta << ")");
      mount_fallback_logged_ = true;
      return true;
    }
  }

  // Detections of another source: checked and queued by stamp until a scan uses them (takeOtherDetections).
  void onOtherDetections(const pmsg::PersonDetections& m) {
    const double stamp = to_seconds(m.header.stamp);
    if (!std::isfinite(stamp) || m.header.frame_id.empty()) {
      warn("fusion_invalid", "'" + fusion_topic_ + "': message without a stamp or frame_id, ignored");
      return;
    }
    OtherDetections o{stamp, m.header.frame_id, {}};
    std::size_t bad = 0;
    for (const auto& d : m.detections) {
      Eigen::Matrix2d c;
      c << d.covariance[0], d.covariance[1], d.covariance[2], d.covariance[3];
      const bool ok = std::isfinite(d.position.x) && std::isfinite(d.position.y) && c.allFinite() && c(0, 0) > 0.0 &&
                      c(1, 1) > 0.0 && std::abs(c(0, 1) - c(1, 0)) <= 1e-9 * (c(0, 0) + c(1, 1)) && c.determinant() > 0.0;
      if (!ok) {
        ++bad;
        continue;
      }
      pt::PersonDetection p;
      p.position = {d.position.x, d.position.y};
      p.covariance = c;
      p.confidence = std::clamp(d.confidence, 0.0, 1.0);
      p.leg_separation = d.leg_separation;
      p.legs = d.leg_count;
      p.source = d.source;
      o.detections.push_back(p);
    }
    if (bad > 0)
      warn("fusion_invalid", "'" + fusion_topic_ + "': " + std::to_string(bad) + " of " +
                                 std::to_string(m.detections.size()) +
                                 " detections with a non-finite position or a covariance that is not symmetric positive definite, skipped");
    if (others_newest_ && o.stamp < *others_newest_) {  // a restarted source: the queued ones are stale
      warn("fusion_back", "'" + fusion_topic_ + "': time went backwards, " + std::to_string(others_.size()) +
                              " queued message(s) dropped");
      others_.clear();
    }
    others_newest_ = o.stamp;
    others_.push_back(std::move(o));
    if (others_.size() > kMaxQueuedOthers) others_.pop_front();  // no scans for a while: keep the newest
    releaseHeldScans();  // a scan may have been waiting for this message
  }

  // Whether the scan at `stamp` may be processed as far as the other source is concerned. Messages of one topic
  // arrive in order, so once one at or after the scan's stamp is in, every message that could pair with the scan
  // is. Until then the scan waits (as in an approximate-time message filter), but only for a source that is
  // lagging, not for one that fell silent: never longer than fusion.wait of scan time (newer scans arriving), and
  // not at all when the newest message is already more than fusion.wait behind the scan or none has come yet.
  [[nodiscard]] bool otherSourceCaughtUp(double stamp, double newest_scan) const {
    if (fusion_topic_.empty() || fusion_wait_ <= 0.0 || !others_newest_) return true;
    const double newest = *others_newest_;
    return newest >= stamp || newest < stamp - fusion_wait_ || newest_scan - stamp >= fusion_wait_;
  }

  // The queued detections of another source for the scan at `stamp`, in the tracking frame (`frame`): the message
  // nearest the scan among those within fusion.max_age of its stamp, used once; the older ones are dropped (a source
  // faster than the laser), the newer ones wait for later scans. Their frame is the tracking frame, the robot's base
  // frame, the scan's frame or any frame with a TF to the base frame; the robot pose is the odometry at their stamp.
  // Approximation: people move up to max_age * 1.5 m/s between the two stamps; nothing compensates that.
  std::vector<pt::PersonDetection> takeOtherDetections(double stamp, const std::string& scan_frame,
                                                       const std::string& tracking_frame) {
    std::optional<std::size_t> best;
    for (std::size_t i = 0; i < others_.size() && others_[i].stamp <= stamp + fusion_max_age_; ++i)
      if (std::abs(others_[i].stamp - stamp) <= fusion_max_age_ &&
          (!best || std::abs(others_[i].stamp - stamp) < std::abs(others_[*best].stamp - stamp)))
        best = i;
    if (!best) {
      std::size_t stale = 0;
      while (!others_.empty() && others_.front().stamp < stamp - fusion_max_age_) others_.pop_front(), ++stale;
      if (stale > 0)
        warn("fusion_stale", "'" + fusion_topic_ + "': " + std::to_string(stale) + " message(s) more than fusion.max_age (" +
                                 std::to_string(fusion_max_age_) + " s) older than the scan at " + std::to_string(stamp) +
                                 " and none within it, dropped");
      return {};
    }
    const OtherDetections o = std::move(others_[*best]);
    others_.erase(others_.begin(), others_.begin() + static_cast<long>(*best) + 1);
    if (o.frame == tracking_frame) return o.detections;
    if (!use_odom_) {  // tracking in the laser frame: nothing else to transform with
      warn("fusion_frame", "'" + fusion_topic_ + "': frame '" + o.frame + "' is not the tracking frame '" +
                               tracking_frame + "' (use_odom is false), dropped");
      return {};
    }
    std::string why;
    const auto robot = robotPoseAt(o.stamp, why);
    if (!robot) {
      warn("fusion_no_odom", "'" + fusion_topic_ + "': " + why + ", dropped");
      return {};
    }
    pt::Pose2 mount{};  // the detections' frame in the base frame
    if (o.frame == scan_frame) {
      mount = mount_;
    } else if (o.frame != base_frame_) {
      try {
        mount = planar(tf_buffer_->lookup(base_frame_, o.frame, cairn::Time{0}));
      } catch (const cairn::TransformError& e) {
        warn("fusion_no_tf", "'" + fusion_topic_ + "': no TF " + base_frame_ + " <- " + o.frame + " (" + e.what() +
                                 "), dropped");
        return {};
      }
    }
    return pt::transformDetections(o.detections, *robot * mount);
  }

  // The static map as the tracker's StaticMap: cells >= the threshold are occupied; the grid's origin pose
  // (possibly rotated) is folded into map_from_tracking together with TF map <- tracking frame per scan.
  void onMap(const nav_msgs::msg::OccupancyGrid& m) {
    const auto w = static_cast<int>(m.info.width), h = static_cast<int>(m.info.height);
    if (w <= 0 || h <= 0 || m.data.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h) ||
        !(m.info.resolution > 0.0F) || !std::isfinite(m.info.origin.position.x) || !std::isfinite(m.info.origin.position.y)) {
      warn("map_invalid", "static map on '" + static_map_topic_ + "': " + std::to_string(w) + " x " + std::to_string(h) +
                              " cells, " + std::to_string(m.data.size()) + " values, resolution " +
                              std::to_string(m.info.resolution) + ": ignored");
      return;
    }
    auto map = std::make_shared<pt::StaticMap>();
    map->width = w;
    map->height = h;
    map->resolution = m.info.resolution;
    map->occupied.resize(m.data.size());
    for (std::size_t i = 0; i < m.data.size(); ++i) map->occupied[i] = m.data[i] >= static_map_threshold_ ? 1 : 0;
    const auto& q = m.info.origin.orientation;
    const double yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
    grid_from_map_ = pt::Pose2{m.info.origin.position.x, m.info.origin.position.y, yaw}.inverse();
    map_frame_ = m.header.frame_id;
    static_map_ = std::move(map);
  }

  // Before each scan: the grid's pose in the tracking frame (identity TF when the map is in that frame).
  void attachStaticMap(const std::string& tracking_frame) {
    if (!static_map_) return;
    pt::Pose2 map_from_tracking{};
    if (!map_frame_.empty() && map_frame_ != tracking_frame) {
      try {
        if (!tf_buffer_) throw cairn::TransformError("no TF listener (use_odom is false)");
        map_from_tracking = planar(tf_buffer_->lookup(map_frame_, tracking_frame, cairn::Time{0}));
      } catch (const cairn::TransformError& e) {
        warn("map_no_tf", "static map: no TF " + map_frame_ + " <- " + tracking_frame + " (" + e.what() +
                              "), scan processed without it");
        tracker_->setStaticMap(nullptr);
        return;
      }
    }
    static_map_->map_from_tracking = grid_from_map_ * map_from_tracking;
    tracker_->setStaticMap(static_map_);
  }

  // At most one warning per key and second, with the number of suppressed repeats.
  void warn(const std::string& key, const std::string& what) {
    auto& w = warnings_[key];
    const auto now = std::chrono::steady_clock::now();
    if (w.count > 0 && now - w.last < std::chrono::seconds(1)) {
      ++w.suppressed;
      return;
    }
    CAIRN_WARN(logger(), what << (w.suppressed ? " (" + std::to_string(w.suppressed) + " similar suppressed)" : ""));
    w.last = now;
    w.suppressed = 0;
    ++w.count;
  }

  void onOdom(const nav_msgs::msg::Odometry& m) {
    const double t = to_seconds(m.header.stamp);
    const auto& p = m.pose.pose;
    if (!std::isfinite(t) || !std::isfinite(p.position.x) || !std::isfinite(p.position.y)) {
      warn("odom_nan", "odom: non-finite stamp or position, ignored");
      return;
    }
    if (!odom_.empty() && t < odom_.back().stamp) {
      warn("odom_back", "odom: time went backwards (" + std::to_string(t) + " < " + std::to_string(odom_.back().stamp) +
                            "), odometry buffer cleared");
      odom_.clear();
    }
    if (!odom_.empty() && t == odom_.back().stamp) odom_.pop_back();
    odom_frame_ = m.header.frame_id;
    const auto& tw = m.twist.twist;
    odom_.push_back({t, pt::Pose2{p.position.x, p.position.y, yaw_of(p.orientation)},
                     std::isfinite(tw.linear.x) ? tw.linear.x : 0.0, std::isfinite(tw.linear.y) ? tw.linear.y : 0.0,
                     std::isfinite(tw.angular.z) ? tw.angular.z : 0.0});
    while (odom_.size() > 2 && odom_.back().stamp - odom_.front().stamp > kOdomHistory) odom_.pop_front();
    releaseHeldScans();
  }

  // Robot (base) pose in the odometry frame at time t: interpolated inside the buffer, extrapolated with the
  // twist up to odom_tolerance beyond it. `pending` (if given) is set when odometry still to come could cover t.
  std::optional<pt::Pose2> robotPoseAt(double t, std::string& why, bool* pending = nullptr) const {
    if (pending) *pending = false;
    if (odom_.empty()) {
      why = "no odometry received yet";
      if (pending) *pending = true;
      return std::nullopt;
    }
    const auto& last = odom_.back();
    if (t >= last.stamp) {
      const double dt = t - last.stamp;
      if (dt > odom_tolerance_) {
        why = "odometry is " + std::to_string(dt) + " s older than the scan (odom_tolerance " + std::to_string(odom_tolerance_) + ")";
        if (pending) *pending = true;
        return std::nullopt;
      }
      const double c = std::cos(last.pose.theta), s = std::sin(last.pose.theta);
      return pt::Pose2{last.pose.x + (c * last.vx - s * last.vy) * dt, last.pose.y + (s * last.vx + c * last.vy) * dt,
                       wrapAngle(last.pose.theta + last.wz * dt)};
    }
    if (t <= odom_.front().stamp) {
      if (odom_.front().stamp - t > odom_tolerance_) {
        why = "scan is older than the odometry buffer";
        return std::nullopt;
      }
      return odom_.front().pose;
    }
    for (std::size_t i = odom_.size() - 1; i > 0; --i) {
      const auto& a = odom_[i - 1];
      const auto& b = odom_[i];
      if (a.stamp <= t && t <= b.stamp) {
        const double u = (t - a.stamp) / (b.stamp - a.stamp);
        return pt::Pose2{a.pose.x + u * (b.pose.x - a.pose.x), a.pose.y + u * (b.pose.y - a.pose.y),
                         wrapAngle(a.pose.theta + u * wrapAngle(b.pose.theta - a.pose.theta))};
      }
    }
    why = "no odometry bracket";
    return std::nullopt;
  }

  void onScan(const sensor_msgs::msg::LaserScan& m) {
    applyPendingParameters();
    pt::LaserScan scan;
    scan.stamp = to_seconds(m.header.stamp);
    scan.angle_min = m.angle_min;
    scan.angle_increment = m.angle_increment;
    scan.range_min = m.range_min;
    scan.range_max = m.range_max;
    scan.ranges = m.ranges;
    // ROS: angle_max = angle_min + (n - 1) * angle_increment; allow one beam of rounding.
    if (std::isfinite(m.angle_increment) && m.angle_increment != 0.0f && !m.ranges.empty()) {
      const double expected = (double(m.angle_max) - m.angle_min) / m.angle_increment + 1.0;
      if (std::abs(expected - static_cast<double>(m.ranges.size())) > 1.5) {
        warn("scan_size", "scan: " + std::to_string(m.ranges.size()) + " ranges but angle_min/max/increment describe " +
                              std::to_string(std::lround(expected)) + " beams, scan ignored");
        return;
      }
    }
    if (!m.intensities.empty() && m.intensities.size() != m.ranges.size()) {
      warn("scan_intensities", "scan: " + std::to_string(m.intensities.size()) + " intensities for " +
                                   std::to_string(m.ranges.size()) + " ranges, scan ignored");
      return;
    }
    try {
      pt::validateScan(scan);
    } catch (const pt::InputError& e) {
      warn("scan_invalid", std::string("scan: ") + e.what() + ", scan ignored");
      return;
    }

    if (use_odom_ && !resolveMount(m.header.frame_id, scan.stamp)) {
      warn("scan_wait_tf", "scan at " + std::to_string(scan.stamp) + ": waiting for TF " + base_frame_ + " <- " +
                               m.header.frame_id + ", scan ignored");
      return;
    }
    // Scans wait here for the odometry of their stamp (as a TF message filter does) and for a lagging other
    // detection source (fusion.topic): these arrive on different topics, and under load they can lag the scans.
    if (!held_.empty() && scan.stamp < held_.back().scan.stamp) {  // a restarted log: the waiting scans are stale
      warn("scan_back", "scan at " + std::to_string(scan.stamp) + ": time went backwards, " +
                            std::to_string(held_.size()) + " waiting scan(s) dropped");
      held_.clear();
    }
    held_.push_back({m, std::move(scan)});
    releaseHeldScans();
  }

  // Processes the held scans, oldest first, while the odometry covers them. A scan waits while the odometry is
  // behind it (or has not arrived yet) and at most odom_queue scans wait: beyond that, or when the odometry can
  // never cover it (older than the buffer), the oldest is dropped with the reason. It also waits for a lagging
  // other source (otherSourceCaughtUp), and is then processed without it at the latest after fusion.wait.
  void releaseHeldScans() {
    while (!held_.empty()) {
      HeldScan& h = held_.front();
      if (!otherSourceCaughtUp(h.scan.stamp, held_.back().scan.stamp) && held_.size() < kMaxHeldScans) return;
      if (!use_odom_) {  // tracking frame = laser frame
        HeldScan next = std::move(h);
        held_.pop_front();
        processScan(next.msg, std::move(next.scan), pt::Pose2{});
        continue;
      }
      std::string why;
      bool pending = false;
      if (const auto robot = robotPoseAt(h.scan.stamp, why, &pending)) {
        pt::Pose2 sensor = *robot * mount_;
        sensor.theta = wrapAngle(sensor.theta);
        HeldScan next = std::move(h);
        held_.pop_front();
        processScan(next.msg, std::move(next.scan), sensor);
        continue;
      }
      if (pending && held_.size() <= static_cast<std::size_t>(odom_queue_)) return;
      warn("scan_no_odom", "scan at " + std::to_string(h.scan.stamp) + ": " + why + ", scan ignored");
      held_.pop_front();
    }
  }

  void processScan(const sensor_msgs::msg::LaserScan& m, pt::LaserScan scan, const pt::Pose2& sensor) {
    const std::string frame = use_odom_ ? odom_frame_ : m.header.frame_id;

    // The static map first: with it attached the detector passes weaker legs (track_leg_confidence_with_map).
    attachStaticMap(frame);
    std::vector<pt::LegDetection> legs;
    try {
      legs = detector_->detectLegs(scan, motion_.get(), sensor, tracker_->hasStaticMap());
      motion_->add(scan, sensor);
    } catch (const pt::InputError& e) {
      warn("scan_invalid", std::string("scan: ") + e.what() + ", scan ignored");
      return;
    }
    // Published detections: the detector's own pairing (laser frame); tracking pairs the legs with the tracks.
    const std::vector<pt::PersonDetection> dets = pt::pairLegs(legs, detector_->params());
    const pt::TrackerStatus st = tracker_->updateLegs(scan.stamp, legs, sensor, detector_->params(), &scan,
                                                      takeOtherDetections(scan.stamp, m.header.frame_id, frame));
    if (st.reset) warn("tracker_reset", "tracker reset: " + st.reason);
    last_tracks_ = tracker_->outputTracks();
    last_sensor_ = sensor;
    last_stamp_ = scan.stamp;
    // The guide tracker sees every track, coasting ones too: outputTracks() omits a track after publish_coast_time
    // (0.25 s), which made every short dropout "lost: track deleted" before guide.lost_timeout could apply.
    const pt::GuideStatus gs = guide_->update(tracker_->tracks(), sensor, scan.stamp);
    if (!gs.event.empty()) CAIRN_INFO(logger(), "guide " << gs.guide_id << ": " << gs.event);

    auto dmsg = std::make_unique<pmsg::PersonDetections>();
    dmsg->header = m.header;
    for (std::size_t i = 0; i < dets.size(); ++i) {
      const auto& d = dets[i];
      pmsg::PersonDetection o;
      o.detection_id = static_cast<uint32_t>(i);
      o.position.x = d.position.x();
      o.position.y = d.position.y();
      o.covariance = {d.covariance(0, 0), d.covariance(0, 1), d.covariance(1, 0), d.covariance(1, 1)};
      o.confidence = d.confidence;
      o.leg_separation = d.leg_separation;
      o.leg_count = static_cast<uint8_t>(d.legs);
      o.source = d.source;
      dmsg->detections.push_back(o);
    }
    det_pub_->publish(std::move(dmsg));

    auto tmsg = std::make_unique<pmsg::TrackedPersons>();
    tmsg->header.stamp = m.header.stamp;
    tmsg->header.frame_id = frame;
    for (const auto& t : last_tracks_) {
      pmsg::TrackedPerson o;
      o.track_id = static_cast<uint32_t>(t.id);
      o.position.x = t.position().x();
      o.position.y = t.position().y();
      o.velocity.x = t.velocity().x();
      o.velocity.y = t.velocity().y();
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) o.covariance[static_cast<std::size_t>(4 * r + c)] = t.covariance(r, c);
      o.age = t.age();
      o.confidence = t.confidence;
      o.leg_separation = t.leg_separation;
      o.stamp = time_from_seconds(t.stamp);
      tmsg->tracks.push_back(o);
    }
    track_pub_->publish(std::move(tmsg));

    auto gmsg = std::make_unique<pmsg::GuideState>();
    gmsg->header.stamp = m.header.stamp;
    gmsg->header.frame_id = frame;
    gmsg->state = gs.state == pt::GuideState::kTracking     ? pmsg::GuideState_Constants::TRACKING
                  : gs.state == pt::GuideState::kPersonLost ? pmsg::GuideState_Constants::PERSON_LOST
                                                            : pmsg::GuideState_Constants::SEARCH;
    gmsg->track_id = gs.state == pt::GuideState::kSearch ? -1 : gs.guide_id;
    gmsg->distance = gs.distance;
    gmsg->bearing = gs.bearing;
    if (gs.track) {
      gmsg->position.x = gs.track->position().x();
      gmsg->position.y = gs.track->position().y();
    }
    gmsg->event = gs.event;
    guide_pub_->publish(std::move(gmsg));

    // Person masking (Yuan §3.2.1): circles of r_P (from the leg spacing) around the people, in the laser frame.
    std::vector<pt::MaskCircle> circles;
    for (const auto& t : last_tracks_) {
      if (mask_mode_ == "none") break;
      if (mask_mode_ == "guide" && !(gs.state == pt::GuideState::kTracking && t.id == gs.guide_id)) continue;
      circles.push_back({sensor.inverseTransform(t.position()), pt::personRadius(t.leg_separation, mask_)});
    }
    pt::maskScan(scan, circles, mask_kind_);
    auto smsg = std::make_unique<sensor_msgs::msg::LaserScan>(m);
    smsg->ranges = std::move(scan.ranges);
    masked_pub_->publish(std::move(smsg));
  }

  void onFollow(const psrv::Follow_Request& rq, psrv::Follow_Response& rs) {
    namespace C = psrv::Follow_Request_Constants;
    switch (rq.command) {
      case C::CLOSEST_IN_FRONT:
        rs.success = guide_->selectClosestInFront(last_tracks_, last_sensor_, last_stamp_);
        if (!rs.success) rs.message = "nobody in front within guide.select_max_distance";
        break;
      case C::TRACK_ID:
        rs.success = guide_->selectId(static_cast<int>(rq.track_id), last_tracks_, last_stamp_);
        if (!rs.success) rs.message = "no published track " + std::to_string(rq.track_id);
        break;
      case C::RELEASE:
        guide_->release();
        rs.success = true;
        break;
      default:
        rs.success = false;
        rs.message = "unknown command " + std::to_string(rq.command) + " (0 closest in front, 1 track id, 2 release)";
    }
    rs.track_id = guide_->state() == pt::GuideState::kSearch ? -1 : guide_->guideId();
    if (rs.success) CAIRN_INFO(logger(), "follow: guide is now " << rs.track_id);
  }

  static constexpr double kOdomHistory = 5.0;  // s of odometry kept for interpolation

  struct WarnState {
    std::chrono::steady_clock::time_point last{};
    std::size_t count = 0, suppressed = 0;
  };

  bool use_odom_ = true;
  double odom_tolerance_ = 0.2;
  int odom_queue_ = 10;
  struct HeldScan {
    sensor_msgs::msg::LaserScan msg;
    pt::LaserScan scan;  // validated, from msg
  };
  std::deque<HeldScan> held_;  // scans waiting for their odometry or other source, oldest first (releaseHeldScans)
  static constexpr std::size_t kMaxHeldScans = 1000;  // bounds fusion.wait's queue for any scan rate
  pt::Pose2 mount_;
  std::string base_frame_;
  double tf_timeout_ = 1.0;
  bool mount_from_tf_ = false, mount_fallback_logged_ = false;
  std::optional<double> first_scan_stamp_;
  std::shared_ptr<cairn::TransformBuffer> tf_buffer_;
  std::string static_map_topic_;
  int static_map_threshold_ = 65;
  std::string fusion_topic_;
  double fusion_max_age_ = 0.15;
  double fusion_wait_ = 0.5;
  std::deque<OtherDetections> others_;  // messages of fusion.topic not yet used or dropped, by stamp
  std::optional<double> others_newest_;  // stamp of the newest message of fusion.topic received
  static constexpr std::size_t kMaxQueuedOthers = 200;
  std::shared_ptr<pt::StaticMap> static_map_;  // shared with the tracker; its map_from_tracking is set per scan
  pt::Pose2 grid_from_map_{};
  std::string map_frame_;
  std::unique_ptr<cairn::TransformListener> tf_listener_;
  std::string mask_mode_;
  pt::MaskParams mask_;
  pt::MaskMode mask_kind_ = pt::MaskMode::kReturnsInside;
  std::shared_ptr<const pt::LegClassifier> classifier_;
  std::unique_ptr<pt::PersonDetector> detector_;
  std::unique_ptr<pt::MotionEvidence> motion_;  // earlier scans in the tracking frame (detector's motion evidence)
  pt::DetectorParams detector_params_;  // staged by the run-time setters (applyPendingParameters)
  pt::GuideParams guide_params_;
  std::map<std::string, std::function<void(const cairn::ParameterValue&)>> runtime_setters_;
  std::mutex pending_mu_;
  std::map<std::string, cairn::ParameterValue> pending_;  // accepted changes not yet applied
  std::unique_ptr<pt::PeopleTracker> tracker_;
  std::unique_ptr<pt::GuideTracker> guide_;
  std::deque<OdomSample> odom_;
  std::string odom_frame_ = "odom";
  std::vector<pt::Track> last_tracks_;
  pt::Pose2 last_sensor_;
  double last_stamp_ = 0.0;
  std::map<std::string, WarnState> warnings_;
  std::shared_ptr<cairn::Publisher<pmsg::PersonDetections>> det_pub_;
  std::shared_ptr<cairn::Publisher<pmsg::TrackedPersons>> track_pub_;
  std::shared_ptr<cairn::Publisher<pmsg::GuideState>> guide_pub_;
  std::shared_ptr<cairn::Publisher<sensor_msgs::msg::LaserScan>> masked_pub_;
  std::shared_ptr<cairn::Subscription<sensor_msgs::msg::LaserScan>> scan_sub_;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<cairn::Subscription<nav_msgs::msg::OccupancyGrid>> map_sub_;
  std::shared_ptr<cairn::Subscription<pmsg::PersonDetections>> other_sub_;
  std::shared_ptr<cairn::Service<psrv::Follow_Request, psrv::Follow_Response>> follow_srv_;
};

}  // namespace cairn_people_tracking

CAIRN_REGISTER_COMPONENT(cairn_people_tracking::PeopleTracker)
