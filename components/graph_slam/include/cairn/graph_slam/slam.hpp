// 2D laser graph SLAM (issue 5): local SLAM (probability-grid submaps, scan matching; local_slam.hpp) feeds a
// pose graph of scan nodes with consecutive-node constraints; loop closures follow Stüde §3.2 adapted to 2D:
//  - candidate nodes within the adaptive radius r = r_min + β·2√(5.991·λ_max) around the current estimate,
//    λ_max from the position covariance accumulated since the last loop closure (Stüde eq. 3.8, App. A);
//  - candidates screened by the learned verifier (descriptor + AdaBoost, Stüde §3.2.1; loop_verifier.hpp);
//  - geometric matching of the node's scan against the candidate's finished submap with branch-and-bound
//    over a window covering the search radius, then grid refinement (correlative_matcher.hpp, grid_refiner.hpp);
//    information Ω from the residuals (Stüde §3.2.2: Ω = I/σ̂², σ̂ from the median absolute deviation of the
//    distances of the matched points to the map's occupied cells);
//  - loop edges carry a robust kernel (`loop_kernel`, default DCS; Huber selectable); the graph is re-optimized
//    with the cairn optimizer (warm-started).
// A loaded map (load()) can be extended in a new session (a new trajectory found by a global search with
// Stüde's α_min / n_start / n_ver / r_ver verification rule) or used for localization only. When local SLAM
// loses track (LocalSlamOptions::lost_scans unmatched scans: kidnapped), a new trajectory starts and is
// placed by the same global search (Stüde §3.2.1: "global search when the robot is lost").
//
// Not thread-safe; the component serializes calls.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/local_slam.hpp"
#include "cairn/graph_slam/occupancy_grid.hpp"
#include "cairn/graph_slam/optimizer.hpp"
#include "cairn/graph_slam/pose_graph.hpp"
#include "cairn/graph_slam/relations.hpp"
#include "cairn/graph_slam/scan_descriptor.hpp"
#include "cairn/sim/types.hpp"

namespace cairn::graph_slam {

class LoopVerifier;

struct SlamOptions {
  /// Local SLAM. The refiner's odometry prior differs from LocalSlamOptions' Cartographer defaults (10, 40):
  /// on ACES a weak rotation prior lets the scan fix heading (rot. error 0.90° → 0.34°) while a moderate
  /// translation prior keeps corridors from collapsing (see README, "Tuning on ACES").
  LocalSlamOptions local = [] {
    LocalSlamOptions l;
    l.refine.translation_weight = 1.0;
    l.refine.degenerate_translation_weight = 3.0;
    l.refine.rotation_weight = 1.0;
    return l;
  }();
  /// Laser mount: pose of the laser frame in the base frame (the component reads it from TF).
  Pose2 sensor_in_base;

  // ---- consecutive-node constraints
  /// Standard deviations added to the matcher's covariance of the relative motion between consecutive nodes
  /// (m, rad per metre travelled, rad). Not in the thesis: chosen, see README.
  double odom_sigma_xy = 0.01;
  double odom_sigma_theta = 0.004;

  // ---- loop-closure search (Stüde §3.2.1, Appendix A "Indoor")
  bool loop_closure = true;
  double r_min = 3.0;   ///< m, minimum search radius (App. A)
  double beta = 0.25;   ///< scale of the uncertainty-dependent part (App. A)
  double r_max = 12.0;  ///< m, cap on the radius (not in the thesis; bounds the matching window)
  /// Try loop closure on every n-th node (1 = every node).
  int loop_node_stride = 3;
  /// Candidate nodes must be at least this old (s) and must not share a submap with the newest node.
  double loop_min_time_gap = 20.0;
  /// At most this many verified candidates (best verifier score first, distinct submaps) are matched per node.
  int loop_max_matches = 2;
  /// Use the learned verifier (Stüde §3.2.1) to screen candidates; without it every candidate is matched.
  bool use_verifier = true;
  std::string verifier_model;  ///< empty: the shipped model
  /// Added to the model's threshold on the boosted score (0: the model's own, chosen for FPR ≤ 1 %, see README).
  double verifier_threshold_offset = 0.0;
  /// Branch-and-bound: minimum mean matching value of the scan in the candidate submap (0..1).
  double loop_min_score = 0.6;
  /// Half width of the angular search window (rad) of the local search.
  double loop_angular_window = 0.5236;  ///< 30°
  int bnb_depth = 7;
  /// Refinement of the branch-and-bound result against the candidate submap (no motion prior: tiny weights).
  RefineOptions loop_refine = [] {
    RefineOptions r;
    r.translation_weight = 1e-3;
    r.rotation_weight = 1e-3;
    return r;
  }();
  /// Minimum σ̂ of the loop information (m); guards against overconfident edges from near-perfect matches.
  double loop_min_sigma = 0.02;
  /// Robust kernel of loop edges ("huber:1", "dcs:1", "cauchy:1", "none"; robust_kernel.hpp). DCS
  /// (Agarwal et al. 2013) scales a loop's information down as it disagrees with the rest of the graph.
  std::string loop_kernel = "dcs:1";
  /// A local loop is added only once this many further matches (from other nodes, within
  /// loop_confirm_window nodes) agree with it on the correction of the trajectory (within loop_confirm_translation
  /// / loop_confirm_rotation): a single match in a repetitive corridor is not trusted. 0 adds every match.
  int loop_confirmations = 1;
  int loop_confirm_window = 30;
  double loop_confirm_translation = 0.3;
  double loop_confirm_rotation = 0.05;
  /// Two matches whose translation information is degenerate (λ_min/λ_max below this: a corridor) do not confirm
  /// each other: neighbouring scans of a corridor alias alike along its axis. One of them must constrain both
  /// directions (ours; chosen on the Freiburg logs, docs/benchmarks.md). 0: off.
  double loop_confirm_min_axis_ratio = 0.3;
  /// Re-admission of agreeing loops (ours, after the pairwise consistency of PCM, Mangelson et al. ICRA 2018).
  /// DCS judges each loop against the current estimate, so a run of correct loops that all ask for the same
  /// large correction (drift along a corridor, a trajectory placed by a global search) is switched off loop by
  /// loop. After an optimization, loops of the last loop_readmit_window nodes that it left with a residual χ²
  /// above loop_readmit_chi2 are checked pairwise: two agree when the cycle loop i → estimated path between the
  /// query nodes → loop j back → estimated path between the targets closes within loop_confirm_translation /
  /// loop_confirm_rotation. At least loop_readmit_min_set mutually agreeing loops whose query nodes span
  /// loop_readmit_min_span metres get loop_readmit_kernel, and the graph is optimized again. 0 disables.
  int loop_readmit_min_set = 6;
  int loop_readmit_window = 90;
  double loop_readmit_chi2 = 11.34;  ///< χ²₃ 99 %
  double loop_readmit_min_span = 2.0;
  std::string loop_readmit_kernel = "huber:1";
  /// Local search: candidates whose boosted verifier score is below this are not matched (the strict model
  /// threshold is kept for the global search, where nothing else constrains a match; inside the eq. 3.8 radius
  /// the geometric match and the confirmation rule do the rest).
  double verifier_local_threshold = 0.0;

  // ---- global search (new session on a loaded map, or lost) — Stüde §3.2.1, Appendix A
  double alpha_min = 0.5;   ///< local search once n_local / n_WM ≥ α_min ...
  int n_start = 3;          ///< ... and n_start loops linked the trajectory to the map
  int n_ver = 2;            ///< a global detection needs n_ver agreeing detections ...
  double r_ver = 5.0;       ///< ... whose target nodes lie within r_ver (m)
  double global_min_score = 0.65;  ///< BnB score for global (full-submap) matching

  // ---- optimization
  /// Re-optimize after this many new nodes even without a loop (0 = only after loops and at finish()).
  int optimize_every_n_nodes = 200;
  OptimizerOptions optimizer;

  // ---- map
  double map_resolution = 0.05;

  /// Localization only: match against the loaded map, never add nodes to it.
  bool localization_only = false;

  // ---- long-term operation (not in the thesis; chosen, see README "Long-term operation")
  /// Mapping mode: where the graph already has a node within revisit_radius (m) and revisit_angle (rad) of the
  /// robot that is older than loop_min_time_gap (or of another trajectory), inserted scans become no nodes: the
  /// robot localizes against the map there, as in localization-only mode, and the graph grows only where the
  /// map is new. A robot patrolling mapped ground then keeps a bounded graph (memory, loop search, optimization
  /// and map rebuild stop growing with time). 0: off, every inserted scan becomes a node.
  double revisit_radius = 0.0;
  /// Heading difference within which a node counts as the same view (π: any, for 360° lasers).
  double revisit_angle = 3.14159265358979323846;
  /// With revisit_radius: a new session on a loaded map (or a new trajectory after a lost event) first tries to
  /// find itself in the map for up to this many inserted scans without adding nodes, as localization does
  /// (global search with the scan as query); linked, it goes on as on mapped ground. Only if that fails (new
  /// ground) does it add nodes, which are then linked by the node-based global search. Without this, every
  /// session left the nodes it mapped before its link in the graph (7-8 per replay of ACES). 0: nodes from the
  /// first scan.
  int revisit_link_scans = 50;
  /// load(): keep the loaded sessions' scan records (the pose of every scan, 40 bytes each: trajectory(),
  /// poses.txt). false drops them, so a state saved again holds the map (nodes, submaps, edges) and only the new
  /// session's scan poses: a robot that reloads and re-saves its map every day then keeps a bounded file.
  bool load_scan_records = true;
};

/// Whether two local loop matches confirm each other (SlamOptions::loop_confirmations): they agree on the query
/// trajectory's placement (implied map->local transforms within loop_confirm_translation / _rotation) and at
/// least one of them is not degenerate along an axis (its translationInformationRatio is at least
/// loop_confirm_min_axis_ratio).
bool loopMatchesConfirm(const Pose2& a_map_to_local, double a_axis_ratio, const Pose2& b_map_to_local,
                        double b_axis_ratio, const SlamOptions& o);

/// λ_min / λ_max of the translation block of an information matrix: near 0 when a match is degenerate along one
/// axis (a corridor), 1 when it constrains both directions alike.
double translationInformationRatio(const Eigen::Matrix3d& information);

enum class EdgeKind : std::uint8_t { kSequential = 0, kLoop = 1, kPrior = 2 };

struct SlamNode {
  std::int64_t id = 0;
  int trajectory = 0;
  double stamp = 0.0;
  Pose2 local_pose;   ///< base in its trajectory's local SLAM frame
  Pose2 global_pose;  ///< optimized (map frame)
  RangeData range_data;                        ///< base frame, filtered (inserted into submaps and the map)
  std::vector<Eigen::Vector2d> matching_points;  ///< downsampled, base frame
  ScanDescriptor descriptor;
  int submap = -1;  ///< index into submaps() of the oldest submap it went into
};

struct SlamSubmap {
  int trajectory = 0;
  Pose2 local_pose;  ///< grid frame in its trajectory's local frame
  std::shared_ptr<const Submap> submap;
  std::vector<std::int64_t> nodes;  ///< nodes inserted into it
  bool finished = false;
};

struct SlamEdge {
  std::int64_t from = 0, to = 0;
  EdgeKind kind = EdgeKind::kSequential;
  Pose2 z;  ///< pose of `to` in the frame of `from`
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
  double score = 0.0;  ///< loops: matching score
};

/// Pose of every scan handed to addScan (also scans that were not nodes): node + relative pose.
struct ScanRecord {
  double stamp = 0.0;
  std::int64_t node = 0;
  Pose2 relative;  ///< base at this scan in the frame of `node`
};

struct SlamStats {
  std::size_t scans = 0, scans_rejected = 0, nodes = 0, submaps = 0;
  std::size_t loop_searches = 0;       ///< nodes for which a loop search ran
  std::size_t loop_candidates = 0;     ///< candidate nodes within the radius
  std::size_t verifier_rejected = 0;   ///< screened out by the verifier
  std::size_t loop_matches = 0;        ///< geometric matches attempted
  std::size_t loops_accepted = 0;
  std::size_t loops_rejected = 0;      ///< matched but below the score
  std::size_t global_detections = 0;   ///< global-search detections (before verification)
  std::size_t optimizations = 0;
  double optimize_time_s = 0.0, loop_time_s = 0.0, local_time_s = 0.0;
  double last_radius = 0.0;            ///< r of eq. 3.8 at the last search
  std::size_t local_recoveries = 0;    ///< scans the branch-and-bound recovery search re-placed
  std::size_t scans_unmatched = 0;     ///< scans below the unmatched score (dead reckoning, not inserted)
  std::size_t lost_events = 0;         ///< lost detections (each started a global search)
  std::size_t revisit_scans = 0;       ///< inserted scans on mapped ground that became no node (revisit_radius)
  std::size_t localization_matches = 0;  ///< matches of a scan (no node) to the map taken (localization, revisits)
  std::size_t localization_gated = 0;    ///< such matches not taken: beyond χ²₃ 99.9 % of the predicted pose
  std::size_t loops_readmitted = 0;      ///< loop edges given loop_readmit_kernel (agreeing, left suppressed by DCS)
};

struct ScanUpdate {
  bool node_added = false;
  std::int64_t node = -1;
  Pose2 pose;  ///< map frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< accumulated since the last loop closure
  int loops_added = 0;
  bool optimized = false;
  bool localized = true;  ///< false while a new session is not yet linked to the loaded map
};

/// Recall of the loop closing on true revisits: of the geometric match attempts whose query and candidate nodes
/// are within `max_distance` in the final solution (the same place), how many matched and how many became loops.
struct LoopRecall {
  std::size_t revisits = 0, matched = 0, accepted = 0;
};

class GraphSlam {
 public:
  /// Throws std::runtime_error if the verifier model cannot be loaded (use_verifier).
  explicit GraphSlam(SlamOptions options = {});
  ~GraphSlam();
  GraphSlam(GraphSlam&&) noexcept;
  GraphSlam& operator=(GraphSlam&&) noexcept;

  /// Processes one scan. odom: odometry pose of the base at the scan's stamp, if known. Bad scans (too few
  /// valid beams, time going backwards) return std::nullopt with the reason in lastError(); never throws on
  /// data.
  std::optional<ScanUpdate> addScan(const sim::LaserScan& scan, const std::optional<Pose2>& odom);
  /// Optimizes the whole graph now.
  OptimizerSummary optimize();
  /// Final optimization (call at the end of a run).
  void finish();
  /// An initial guess of the robot's pose in the map (e.g. RViz-style "initial pose"): the next scan is placed
  /// there, and the loop search around it is local instead of global (Stüde §3.2.1: local search needs a link
  /// or an initial guess). In localization mode this (re)localizes immediately.
  void setInitialPose(const Pose2& pose);
  /// True once the current trajectory is placed in the map (always for a fresh map).
  bool localized() const;
  /// Sets the laser mount (pose of the laser in the base frame) for the following scans (the component learns it
  /// from TF after construction, possibly after a state was loaded).
  void setSensorInBase(const Pose2& sensor_in_base);

  /// Pose of every scan added so far (map frame, stamps of the scans).
  std::vector<StampedPose> trajectory() const;
  /// Occupancy grid from all nodes at their optimized poses (all trajectories).
  OccupancyGrid map() const;
  /// Current pose of the robot base in the map frame (last scan), and map -> local frame of the current trajectory.
  /// The local frame is the odometry frame only if the first scan came with odometry (and as far as scan matching
  /// has not corrected it since); the component publishes map->odom as map pose x odometry pose^-1 instead.
  Pose2 currentPose() const;
  Pose2 mapToLocal() const;

  const std::vector<SlamNode>& nodes() const;
  const std::vector<SlamSubmap>& submaps() const;
  const std::vector<SlamEdge>& edges() const;
  const PoseGraph& graph() const;
  const SlamStats& stats() const;
  const SlamOptions& options() const;
  const std::string& lastError() const;

  /// Loop edges whose constraint disagrees with the current (final) solution by more than these bounds
  /// (translation m, rotation rad): the precision measure of issue 5.
  std::size_t inconsistentLoops(double max_translation = 0.3, double max_rotation = 0.0524) const;
  LoopRecall loopRecall(double max_distance = 1.0) const;

  /// Saves the whole state (options that shape the map, nodes with scans, edges, submap membership, scan
  /// records) in a versioned binary file. Throws std::runtime_error "path: what".
  void save(const std::string& path) const;
  /// Loads a saved state; mapping continues in a new trajectory (multi-session) or, with
  /// options.localization_only, localizes against it. Throws std::runtime_error "path: what" for missing,
  /// truncated, corrupt or other-version files.
  static GraphSlam load(const std::string& path, SlamOptions options);

  /// The file format version save() writes and load() reads.
  static constexpr std::uint32_t kFileVersion = 1;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cairn::graph_slam
