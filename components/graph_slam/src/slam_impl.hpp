// Private state of GraphSlam, shared by src/slam.cpp (pipeline) and src/slam_io.cpp (save/load).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "cairn/graph_slam/correlative_matcher.hpp"
#include "cairn/graph_slam/local_slam.hpp"
#include "cairn/graph_slam/loop_verifier.hpp"
#include "cairn/graph_slam/optimizer.hpp"
#include "cairn/graph_slam/slam.hpp"

namespace cairn::graph_slam {

/// What a loop search matches: a node of the graph, or (localization) the current scan.
struct LoopQuery {
  int trajectory = 0;
  double stamp = 0.0;
  Pose2 global_guess;
  Pose2 local_pose;  ///< query base in its trajectory's local frame
  const std::vector<Eigen::Vector2d>* points = nullptr;  ///< base frame
  const ScanDescriptor* descriptor = nullptr;
  std::int64_t node = -1;  ///< -1 for a localization query
  int own_submap = -1;     ///< submaps never matched (the query's own)
};

/// A geometric match of a query against a candidate's submap: pose of the query in candidate node k's frame.
struct LoopMatch {
  std::int64_t target = 0;  ///< candidate node k
  int submap = 0;
  Pose2 z;                  ///< query base in the frame of k
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
  double score = 0.0;
  Pose2 implied_query_global;  ///< global(k) ∘ z
  Pose2 implied_map_to_local;  ///< the query trajectory's local frame in the map frame, as this match implies
  std::int64_t query = -1;     ///< query node (-1: localization query)
  double axis_ratio = 1.0;     ///< translationInformationRatio(information): near 0 along a corridor
};

/// A loop-closure candidate node and its ranking score (verifier score, or −distance without a verifier).
struct LoopCandidate {
  std::int64_t node = 0;
  double score = 0.0;
};

/// A geometric match attempt (for the recall measure): query node, candidate node, outcome.
struct LoopAttempt {
  std::int64_t query = -1, target = -1;
  bool matched = false;   ///< branch and bound + refinement passed
  bool accepted = false;  ///< became a loop edge
};

struct SubmapCache {
  std::unique_ptr<BranchAndBoundMatcher> bnb;  ///< built when first matched (finished submaps only)
  std::vector<float> distance;                 ///< m to the nearest occupied cell, grid layout; empty until needed
};

struct GraphSlam::Impl {
  explicit Impl(SlamOptions o);

  SlamOptions options;
  std::optional<LoopVerifier> verifier;
  DescriptorOptions descriptor_options;
  std::unique_ptr<LocalSlam> local;
  int trajectory = 0;
  int submap_base = 0;  ///< submaps() index of the current LocalSlam's submap 0
  std::optional<std::int64_t> last_node;  ///< newest node of the current trajectory
  Pose2 map_to_local;                     ///< current trajectory's local frame in the map frame
  bool linked = true;                     ///< current trajectory connected to the rest of the map
  int links = 0;                          ///< verified links of the current trajectory to older ones
  std::vector<LoopMatch> pending_global;  ///< unverified global detections (Stüde n_ver rule)
  std::vector<LoopMatch> pending_local;   ///< local matches waiting for loop_confirmations agreeing ones
  RobustKernel loop_kernel;
  RobustKernel readmit_kernel;
  /// Loop edges of this session with their factor in `graph` (re-admission changes their kernel).
  struct LoopFactor {
    std::size_t edge = 0, factor = 0;
    bool readmitted = false;
  };
  std::vector<LoopFactor> loop_factors;
  /// Index of the current trajectory's first node: nodes before it are the working memory it must be linked
  /// to (earlier sessions after load(), earlier trajectories after a lost event). α = n_local / n_WM uses it.
  std::size_t trajectory_first_node = 0;

  std::vector<SlamNode> nodes;  ///< node id == index
  std::vector<SlamSubmap> submaps;
  std::vector<SubmapCache> caches;
  std::vector<SlamEdge> edges;
  std::vector<ScanRecord> records;
  std::vector<LoopAttempt> attempts;
  std::vector<StampedPose> localization_poses;  ///< localization mode: poses of scans (no nodes)
  PoseGraph graph;
  Optimizer optimizer;
  SlamStats stats;
  std::string last_error;
  Eigen::Matrix3d cov_since_loop = Eigen::Matrix3d::Zero();
  int nodes_since_optimize = 0;
  Pose2 current_pose;
  std::optional<Pose2> initial_pose;  ///< applied at the next scan (setInitialPose)
  std::vector<sim::LaserScan> held_scans;  ///< raw scans of LocalSlam's held-back (unmatched) results, in order
  std::optional<Pose2> restart_anchor;  ///< after restartLost(): map pose the next scan continues from
  /// On mapped ground (revisit_radius): the nearest older node, to which the scans are recorded (a record
  /// hangs off its node: the nearest keeps a later optimization's rotation of a far node from swinging it).
  std::optional<std::int64_t> revisit_anchor;
  bool revisited_since_node = false;  ///< the next node follows a revisit: placed by the localized pose
  std::optional<Pose2> localized_at;  ///< local pose of the last scan matchToMap() predicted to (process noise)
  /// revisit_link_scans: scans of the current trajectory taken while it looked for itself in the map without
  /// nodes (stamp, local pose), and how many inserted scans that search has used.
  std::vector<std::pair<double, Pose2>> prelink_scans;
  int prelink_inserted = 0;
  std::vector<LoopMatch> prelink_links;  ///< its verified global detections so far (n_start must agree)
  /// Records for prelink_scans: relative to the nearest node at their map pose (once linked), or to the
  /// trajectory's first node (`node`, when it gave up and started mapping).
  void flushPrelinkScans(std::optional<std::int64_t> node);
  void applyInitialPose(const Pose2& local_pose);
  /// The scan's answer: current_pose with the covariance since the last loop, and whether the trajectory is linked.
  void reportPose(ScanUpdate& update) const;

  // pipeline (slam.cpp)
  std::optional<ScanUpdate> addScan(const sim::LaserScan& scan, const std::optional<Pose2>& odom);
  std::int64_t addNode(const LocalResult& r, const sim::LaserScan& scan);
  /// addNode + loop search + finished submaps + optimization trigger (one inserted scan).
  void takeNode(const LocalResult& r, const sim::LaserScan& scan, ScanUpdate& update);
  void syncSubmaps(const LocalResult& r, std::int64_t node);
  int searchLoops(std::int64_t node);
  std::vector<LoopMatch> localSearch(const LoopQuery& q, double radius, double verifier_threshold);
  std::vector<LoopMatch> confirmLocal(const std::vector<LoopMatch>& fresh);
  std::vector<LoopMatch> globalSearch(const LoopQuery& q);
  /// Matches the query against the submaps of ranked candidates, one candidate per submap, at most max_tries
  /// submaps (window nullptr: the whole submap).
  std::vector<LoopMatch> matchCandidates(const LoopQuery& q, const std::vector<LoopCandidate>& ranked,
                                         const SearchWindow* window, double min_score, int max_tries);
  std::optional<LoopMatch> matchSubmap(const LoopQuery& q, std::int64_t target, const SearchWindow* window,
                                       double min_score);
  bool verifyGlobal(const std::vector<LoopMatch>& fresh, std::vector<LoopMatch>& agreeing);
  void addLoopEdge(std::int64_t node, const LoopMatch& m);
  /// loop_readmit_*: gives the largest set of recent, mutually agreeing loops the optimization left suppressed
  /// the re-admission kernel; true if it changed a kernel.
  bool readmitAgreeingLoops();
  /// A loop edge's constraint against the current estimate: z⁻¹ ∘ (from⁻¹ ∘ to).
  Pose2 loopResidual(const SlamEdge& e) const;
  void localizeScan(const LocalResult& r, const sim::LaserScan& scan, ScanUpdate& update);
  /// Matches an inserted scan against the map and moves map_to_local to the best match (localization-only
  /// mode, and revisits in mapping mode).
  void matchToMap(const LocalResult& r, const sim::LaserScan& scan, ScanUpdate& update);
  /// revisit_radius: the nearest older node (loop_min_time_gap, or another trajectory) near `pose` (map
  /// frame), if any.
  std::optional<std::int64_t> mappedNodeNear(const Pose2& pose, double stamp) const;
  /// revisit_radius, linked: the node a scan of local SLAM is recorded to instead of becoming a node (mapped
  /// ground), if any.
  std::optional<std::int64_t> revisitAnchor(const LocalResult& r) const;
  /// Takes LocalSlam's newly finished submaps: those with nodes become loop-closure targets, the others (no
  /// node went into them: revisits, localization) are dropped, so LocalSlam holds only its active ones.
  void collectFinishedSubmaps();
  SubmapCache& cache(int submap);
  OptimizerSummary optimize();
  void startTrajectory();
  /// LocalSlam reported lost: a new trajectory (SLAM) or a fresh local tracker (localization) that is placed
  /// by a global search; the pose stays continuous (restart_anchor) until a global link moves it.
  void restartLost();
  double searchRadius() const;
};

/// SE(2) compounding Jacobians of c = a ∘ b w.r.t. a and b (additive x, y, θ parametrization).
void composeJacobians(const Pose2& a, const Pose2& b, Eigen::Matrix3d& ja, Eigen::Matrix3d& jb);

}  // namespace cairn::graph_slam
