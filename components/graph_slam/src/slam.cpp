// 2D laser graph SLAM pipeline (see slam.hpp). Save/load lives in slam_io.cpp.
#include "cairn/graph_slam/slam.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cairn/graph_slam/grid_refiner.hpp"
#include "cairn/graph_slam/probability_grid.hpp"
#include "cairn/graph_slam/scan_filter.hpp"
#include "slam_impl.hpp"

namespace cairn::graph_slam {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

Pose2 between(const Pose2& a, const Pose2& b) { return compose(inverse(a), b); }

/// A relative pose (or error) within the bounds: translation (m) and rotation (rad).
bool within(const Pose2& d, double max_translation, double max_rotation) {
  return !(d.t.norm() > max_translation || std::abs(normalizeAngle(d.theta)) > max_rotation);
}

}  // namespace

bool loopMatchesConfirm(const Pose2& a_map_to_local, double a_axis_ratio, const Pose2& b_map_to_local,
                        double b_axis_ratio, const SlamOptions& o) {
  // Two matches degenerate along an axis (a corridor) alias the same way — neighbouring scans of one corridor
  // are matched equally far off along it — so they are no independent evidence of where along it the loop is.
  if (a_axis_ratio < o.loop_confirm_min_axis_ratio && b_axis_ratio < o.loop_confirm_min_axis_ratio) return false;
  return within(between(a_map_to_local, b_map_to_local), o.loop_confirm_translation, o.loop_confirm_rotation);
}

double translationInformationRatio(const Eigen::Matrix3d& information) {
  const Eigen::Vector2d ev =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(information.topLeftCorner<2, 2>()).eigenvalues();
  return ev(1) > 0.0 ? std::max(0.0, ev(0)) / ev(1) : 0.0;
}

namespace {

/// Global detections agree on where the query trajectory sits when their implied local->map transforms are
/// within these bounds (2D reading of Stüde's r_ver rule; chosen, see README).
constexpr double kPlacementTranslation = 0.5, kPlacementRotation = 0.2;

Eigen::Matrix2d rot(double th) { return rotation2(th); }

}  // namespace

void composeJacobians(const Pose2& a, const Pose2& b, Eigen::Matrix3d& ja, Eigen::Matrix3d& jb) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  ja.setIdentity();
  ja(0, 2) = -s * b.t.x() - c * b.t.y();
  ja(1, 2) = c * b.t.x() - s * b.t.y();
  jb.setIdentity();
  jb.topLeftCorner<2, 2>() = rot(a.theta);
}

GraphSlam::Impl::Impl(SlamOptions o) : options(std::move(o)), optimizer(options.optimizer) {
  try {
    loop_kernel = RobustKernel::parse(options.loop_kernel);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("loop_kernel: ") + e.what());
  }
  try {
    readmit_kernel = RobustKernel::parse(options.loop_readmit_kernel);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("loop_readmit_kernel: ") + e.what());
  }
  if (options.use_verifier && options.loop_closure) {
    verifier = options.verifier_model.empty() ? LoopVerifier::loadDefault() : LoopVerifier::load(options.verifier_model);
    verifier->setThreshold(verifier->threshold() + options.verifier_threshold_offset);
    descriptor_options = verifier->descriptorOptions();
  }
  startTrajectory();
}

void GraphSlam::Impl::startTrajectory() {
  local = std::make_unique<LocalSlam>(options.local);
  submap_base = static_cast<int>(submaps.size());
  last_node.reset();
  localized_at.reset();
  revisit_anchor.reset();
  revisited_since_node = false;
  prelink_scans.clear();
  prelink_inserted = 0;
  prelink_links.clear();
  cov_since_loop.setZero();
  pending_global.clear();
  links = 0;
  trajectory_first_node = nodes.size();
}

void GraphSlam::Impl::restartLost() {
  ++stats.lost_events;
  if (!options.localization_only && last_node) {
    // The old trajectory stays as it is; its active submaps will never change again, so they are finished
    // (loop-closure targets from now on). The new trajectory is unlinked until a global search places it.
    for (SlamSubmap& sm : submaps)
      if (sm.trajectory == trajectory) sm.finished = true;
    ++trajectory;
  }
  startTrajectory();  // localization (or nothing mapped yet in this trajectory): only a fresh local tracker
  linked = nodes.empty();
  restart_anchor = current_pose;
  held_scans.clear();  // LocalSlam discarded the held-back scans
}

double GraphSlam::Impl::searchRadius() const {
  // Stüde eq. 3.8: r = r_min + β · 2√(5.991 λ_max), λ_max of the position covariance since the last closure.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov_since_loop.topLeftCorner<2, 2>());
  const double lambda_max = std::max(0.0, es.eigenvalues().maxCoeff());
  return std::min(options.r_max, options.r_min + options.beta * 2.0 * std::sqrt(5.991 * lambda_max));
}

std::optional<ScanUpdate> GraphSlam::Impl::addScan(const sim::LaserScan& scan, const std::optional<Pose2>& odom) {
  ++stats.scans;
  const auto t0 = Clock::now();
  const RangeData data = toRangeData(scan, options.sensor_in_base, options.local.filter);
  std::optional<LocalResult> r = local->addScan(scan.stamp, data, odom);
  if (r) {
    stats.local_recoveries += r->recovered ? 1 : 0;
    stats.scans_unmatched += r->unmatched ? 1 : 0;
  }
  if (r && r->lost) {
    // Kidnapped, or the world is not where odometry says: this scan starts over (Stüde §3.2.1 global search).
    restartLost();
    r = local->addScan(scan.stamp, data, odom);
  }
  stats.local_time_s += seconds(t0);
  if (r && restart_anchor) {
    // Keep the map pose continuous across the restart (the new local frame starts at this scan).
    map_to_local = compose(*restart_anchor, inverse(r->local_pose));
    restart_anchor.reset();
  }
  if (!r) {
    ++stats.scans_rejected;
    last_error = local->lastError();
    return std::nullopt;
  }
  ScanUpdate update;
  if (initial_pose) applyInitialPose(r->local_pose);
  // revisit_link_scans: a new session (or trajectory after a lost event) looks for itself in the map without
  // adding nodes.
  const bool prelink = options.revisit_radius > 0.0 && !linked && !last_node && trajectory_first_node > 0 &&
                       prelink_inserted < options.revisit_link_scans;
  // Held-back scans that went in now become nodes first, as if they had not been held back.
  if (!r->flushed.empty() && r->flushed.size() == held_scans.size() && !options.localization_only)
    for (std::size_t i = 0; i < r->flushed.size(); ++i) {
      const LocalResult& f = r->flushed[i];
      // While looking for the map, or on mapped ground (revisit_radius), a flushed scan becomes no node either
      // (it has its record already).
      if (!f.inserted || prelink || revisitAnchor(f)) continue;
      takeNode(f, held_scans[i], update);
    }
  if (!r->flushed.empty()) held_scans.clear();
  if (r->held) held_scans.push_back(scan);
  if (options.localization_only) {
    localizeScan(*r, scan, update);
    return update;
  }
  if (prelink) {
    if (r->inserted) {
      ++prelink_inserted;
      matchToMap(*r, scan, update);
      collectFinishedSubmaps();
    }
    prelink_scans.emplace_back(scan.stamp, r->local_pose);
    current_pose = compose(map_to_local, r->local_pose);
    if (linked) flushPrelinkScans(std::nullopt);
    reportPose(update);
    return update;
  }
  if (r->inserted || !last_node)  // (a trajectory linked without nodes must not make its first node of any scan)
    revisit_anchor = revisitAnchor(*r);
  if (revisit_anchor) {
    // Mapped ground (revisit_radius): no node; the scan is matched against the map instead, as in
    // localization-only mode, and recorded relative to the nearest mapped node at its localized pose.
    if (r->inserted) {
      ++stats.revisit_scans;
      matchToMap(*r, scan, update);
      collectFinishedSubmaps();
    }
    revisited_since_node = true;
    current_pose = compose(map_to_local, r->local_pose);
    const SlamNode& anchor = nodes[static_cast<std::size_t>(*revisit_anchor)];
    records.push_back({scan.stamp, anchor.id, between(anchor.global_pose, current_pose)});
    reportPose(update);
    return update;
  }
  if (r->inserted || !last_node) takeNode(*r, scan, update);
  if (!prelink_scans.empty()) flushPrelinkScans(last_node);  // the search without nodes gave up
  const SlamNode& n = nodes[static_cast<std::size_t>(*last_node)];
  const Pose2 rel = between(n.local_pose, r->local_pose);
  records.push_back({scan.stamp, n.id, rel});
  current_pose = compose(n.global_pose, rel);
  map_to_local = compose(n.global_pose, inverse(n.local_pose));
  reportPose(update);
  return update;
}

void GraphSlam::Impl::takeNode(const LocalResult& r, const sim::LaserScan& scan, ScanUpdate& update) {
  const bool after_revisit = revisited_since_node;
  const std::int64_t id = addNode(r, scan);
  update.node_added = true;
  update.node = id;
  int added = 0;
  // The first node after a revisit always searches: its edge to the node before the revisit is long and weak.
  if (options.loop_closure &&
      (static_cast<int>(nodes.size()) % std::max(1, options.loop_node_stride) == 0 || !linked || after_revisit)) {
    added = searchLoops(id);
    update.loops_added += added;
  }
  collectFinishedSubmaps();
  if (added > 0 ||
      (options.optimize_every_n_nodes > 0 && nodes_since_optimize >= options.optimize_every_n_nodes)) {
    optimize();
    update.optimized = true;
  }
}

void GraphSlam::Impl::reportPose(ScanUpdate& update) const {
  update.pose = current_pose;
  update.covariance = cov_since_loop;
  update.localized = linked;
}

void GraphSlam::Impl::applyInitialPose(const Pose2& local_pose) {
  map_to_local = compose(*initial_pose, inverse(local_pose));
  initial_pose.reset();
  linked = true;
  pending_global.clear();
  cov_since_loop.setZero();
  // Nodes of the current trajectory (if any) move with it; the weak prior of its first node follows.
  for (SlamNode& t : nodes)
    if (t.trajectory == trajectory) {
      t.global_pose = compose(map_to_local, t.local_pose);
      graph.setPose2(t.id, t.global_pose);
    }
}

std::int64_t GraphSlam::Impl::addNode(const LocalResult& r, const sim::LaserScan& scan) {
  SlamNode n;
  n.id = static_cast<std::int64_t>(nodes.size());
  n.trajectory = trajectory;
  n.stamp = r.stamp;
  n.local_pose = r.local_pose;
  n.range_data = r.range_data;
  n.matching_points = r.matching_points;
  try {
    n.descriptor = computeDescriptor(scan, descriptor_options);
  } catch (const std::invalid_argument&) {
    n.descriptor = {};  // malformed scan geometry: no verifier candidate (never reached for scans LocalSlam took)
  }
  const bool first_of_trajectory = !last_node.has_value();
  if (first_of_trajectory || revisited_since_node) {
    // After a revisit map_to_local is the localized one: the relative motion since the last node is not.
    n.global_pose = compose(map_to_local, n.local_pose);
  } else {
    const SlamNode& p = nodes[static_cast<std::size_t>(*last_node)];
    n.global_pose = compose(p.global_pose, between(p.local_pose, n.local_pose));
  }
  nodes.push_back(std::move(n));
  SlamNode& node = nodes.back();
  graph.addPose2(node.id, node.global_pose);
  if (first_of_trajectory) {
    if (node.id == 0) {
      graph.setFixed(node.id);
    } else {
      // A new session's first node: a very weak prior keeps the gauge until loops link it to the map.
      SlamEdge e{node.id, node.id, EdgeKind::kPrior, node.global_pose, Eigen::Matrix3d::Identity() * 1e-6, 0.0};
      graph.addPrior2(node.id, e.z, e.information);
      edges.push_back(e);
    }
  } else {
    const SlamNode& p = nodes[static_cast<std::size_t>(*last_node)];
    const Pose2 z = between(p.local_pose, node.local_pose);
    // Relative-motion covariance: the matcher's covariance rotated into the new node's frame (where a
    // between-edge's error lives) plus a floor growing with the distance travelled (chosen, see README).
    const Eigen::Matrix2d R = rot(node.local_pose.theta);
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    S.topLeftCorner<2, 2>() = R.transpose() * r.covariance.topLeftCorner<2, 2>() * R;
    S(2, 2) = r.covariance(2, 2);
    const double d = z.t.norm();
    const double sxy = options.odom_sigma_xy + 0.01 * d;
    const double sth = options.odom_sigma_theta + 0.01 * d;
    S(0, 0) += sxy * sxy;
    S(1, 1) += sxy * sxy;
    S(2, 2) += sth * sth;
    SlamEdge e{p.id, node.id, EdgeKind::kSequential, z, S.inverse(), r.match_score};
    graph.addBetween2(e.from, e.to, e.z, e.information);
    edges.push_back(e);
    // Position uncertainty since the last loop closure (Stüde eq. 3.8's covariance), by compounding.
    Eigen::Matrix3d ja, jb;
    composeJacobians(p.global_pose, z, ja, jb);
    cov_since_loop = ja * cov_since_loop * ja.transpose() + jb * S * jb.transpose();
  }
  last_node = node.id;
  revisited_since_node = false;
  localized_at.reset();
  syncSubmaps(r, node.id);
  ++nodes_since_optimize;
  ++stats.nodes;
  return node.id;
}

void GraphSlam::Impl::syncSubmaps(const LocalResult& r, std::int64_t node) {
  for (const auto& s : r.insertion_submaps) {
    const auto idx = static_cast<std::size_t>(submap_base + s->index);
    while (submaps.size() <= idx) {
      submaps.emplace_back();
      caches.emplace_back();
    }
    SlamSubmap& sm = submaps[idx];
    if (!sm.submap) {
      sm.trajectory = trajectory;
      sm.local_pose = s->local_pose;
      sm.submap = s;
      ++stats.submaps;
    }
    sm.nodes.push_back(node);
    SlamNode& n = nodes[static_cast<std::size_t>(node)];
    if (n.submap < 0 || static_cast<int>(idx) < n.submap) n.submap = static_cast<int>(idx);
  }
}

SubmapCache& GraphSlam::Impl::cache(int submap) {
  SubmapCache& c = caches[static_cast<std::size_t>(submap)];
  const ProbabilityGrid& g = submaps[static_cast<std::size_t>(submap)].submap->grid;
  if (!c.bnb) c.bnb = std::make_unique<BranchAndBoundMatcher>(g, options.bnb_depth);
  if (c.distance.empty() && g.width() > 0 && g.height() > 0) {
    // Distance of every cell to the nearest occupied cell (for σ̂ of Stüde §3.2.2).
    cv::Mat free_mask(g.height(), g.width(), CV_8UC1);
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x)
        free_mask.at<std::uint8_t>(y, x) = (g.known(x, y) && g.probability(x, y) > 0.6) ? 0 : 255;
    cv::Mat dist;
    cv::distanceTransform(free_mask, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    c.distance.assign(dist.begin<float>(), dist.end<float>());
    for (float& v : c.distance) v *= static_cast<float>(g.resolution());
  }
  return c;
}

std::optional<LoopMatch> GraphSlam::Impl::matchSubmap(const LoopQuery& q, std::int64_t target,
                                                      const SearchWindow* window, double min_score) {
  const SlamNode& k = nodes[static_cast<std::size_t>(target)];
  const int si = k.submap;
  const SlamSubmap& sm = submaps[static_cast<std::size_t>(si)];
  SubmapCache& c = cache(si);
  ++stats.loop_matches;
  if (q.node >= 0) attempts.push_back({q.node, target, false, false});
  // Pose of k in the submap's grid frame (same local frame), and the query's predicted pose there.
  const Pose2 sub_k = between(sm.local_pose, k.local_pose);
  const Pose2 predicted = compose(sub_k, between(k.global_pose, q.global_guess));
  const std::optional<MatchResult> m =
      window != nullptr ? c.bnb->match(*q.points, predicted, *window, min_score) : c.bnb->matchFull(*q.points, min_score);
  if (!m) {
    ++stats.loops_rejected;
    return std::nullopt;
  }
  const ProbabilityGrid& g = sm.submap->grid;
  const RefineResult ref = refine(g, *q.points, m->pose, m->pose, options.loop_refine);
  if (ref.score < min_score || (ref.pose.t - m->pose.t).norm() > 0.3) {
    ++stats.loops_rejected;
    return std::nullopt;
  }
  // Ω = I/σ̂² with σ̂ = 1.4826·MAD of the matched points' distances to the nearest occupied cell (Stüde §3.2.2);
  // the rotational part uses σ̂ over the points' median range (2D adaptation, see README).
  std::vector<double> d;
  std::vector<double> ranges;
  d.reserve(q.points->size());
  for (const auto& p : *q.points) {
    const Eigen::Vector2d w = ref.pose.t + rot(ref.pose.theta) * p;
    const CellIndex ci = g.cellIndex(w);
    if (ci.x < 0 || ci.y < 0 || ci.x >= g.width() || ci.y >= g.height()) continue;
    d.push_back(c.distance[static_cast<std::size_t>(ci.y) * static_cast<std::size_t>(g.width()) + static_cast<std::size_t>(ci.x)]);
    ranges.push_back(p.norm());
  }
  if (d.size() < 10) {
    ++stats.loops_rejected;
    return std::nullopt;
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double med = median(d);
  for (double& v : d) v = std::abs(v - med);
  const double sigma = std::max(options.loop_min_sigma, 1.4826 * median(d) + 0.5 * g.resolution());
  // Stüde §3.2.2 treats the registration as one measurement with Ω = I/σ̂². In 2D, corridors make a match
  // degenerate along their axis, so the information keeps the point-to-line structure of the match
  // (pointToLineCovariance), normalized per point so that a well-constrained match gets ≈ I/σ̂² in
  // translation (2D adaptation, see README).
  RefineOptions cov_opt = options.loop_refine;
  cov_opt.point_sigma = sigma * std::sqrt(static_cast<double>(q.points->size()));
  cov_opt.min_sigma_translation = sigma * 0.5;
  cov_opt.min_sigma_rotation = sigma / std::max(1.0, median(ranges));
  const Eigen::Matrix3d cov = pointToLineCovariance(*q.points, ref.pose, cov_opt);
  LoopMatch lm;
  lm.target = target;
  lm.submap = si;
  lm.z = compose(inverse(sub_k), ref.pose);
  // The covariance is in the submap frame; a between-edge's error lives in the frame of its measured pose
  // (Z⁻¹·X_i⁻¹·X_j, pose_graph.hpp), i.e. the query's: rotate by the query's heading in the submap.
  Eigen::Matrix3d Rq = Eigen::Matrix3d::Identity();
  Rq.topLeftCorner<2, 2>() = rot(ref.pose.theta);
  lm.information = (Rq.transpose() * cov * Rq).inverse();
  lm.axis_ratio = translationInformationRatio(lm.information);
  lm.score = ref.score;
  lm.implied_query_global = compose(k.global_pose, lm.z);
  lm.implied_map_to_local = compose(lm.implied_query_global, inverse(q.local_pose));
  lm.query = q.node;
  if (q.node >= 0) attempts.back().matched = true;
  return lm;
}

std::vector<LoopMatch> GraphSlam::Impl::matchCandidates(const LoopQuery& q, const std::vector<LoopCandidate>& ranked,
                                                        const SearchWindow* window, double min_score, int max_tries) {
  std::vector<LoopMatch> out;
  std::vector<int> tried;
  for (const LoopCandidate& c : ranked) {
    if (static_cast<int>(tried.size()) >= max_tries) break;
    const int si = nodes[static_cast<std::size_t>(c.node)].submap;
    if (std::find(tried.begin(), tried.end(), si) != tried.end()) continue;
    tried.push_back(si);
    if (auto m = matchSubmap(q, c.node, window, min_score)) out.push_back(*m);
  }
  return out;
}

std::vector<LoopMatch> GraphSlam::Impl::localSearch(const LoopQuery& q, double radius, double verifier_threshold) {
  std::vector<LoopCandidate> cands;
  const double r2 = radius * radius;
  for (const SlamNode& k : nodes) {
    if (k.id == q.node || k.submap < 0 || k.submap == q.own_submap) continue;
    const SlamSubmap& sm = submaps[static_cast<std::size_t>(k.submap)];
    if (!sm.finished) continue;
    if (k.trajectory == q.trajectory && q.stamp - k.stamp < options.loop_min_time_gap) continue;
    if ((k.global_pose.t - q.global_guess.t).squaredNorm() > r2) continue;
    ++stats.loop_candidates;
    double score = 0.0;
    if (verifier) {
      if (k.descriptor.scalars.empty() || q.descriptor->scalars.empty()) continue;
      score = verifier->score(k.descriptor, *q.descriptor);
      if (score < verifier_threshold) {
        ++stats.verifier_rejected;
        continue;
      }
    } else {
      score = -(k.global_pose.t - q.global_guess.t).norm();  // nearest first
    }
    cands.push_back({k.id, score});
  }
  std::sort(cands.begin(), cands.end(), [](const LoopCandidate& a, const LoopCandidate& b) { return a.score > b.score; });
  SearchWindow w;
  w.linear = radius;
  w.angular = options.loop_angular_window;
  return matchCandidates(q, cands, &w, options.loop_min_score, options.loop_max_matches);
}

std::vector<LoopMatch> GraphSlam::Impl::globalSearch(const LoopQuery& q) {
  // Whole working memory (nodes of other trajectories), screened by the verifier, matched over whole submaps.
  std::vector<LoopCandidate> cands;
  if (!verifier) {
    // No verifier: every finished submap of the other trajectories, through its middle node (expensive:
    // one whole-submap branch-and-bound each).
    for (std::size_t si = 0; si < submaps.size(); ++si) {
      const SlamSubmap& sm = submaps[si];
      if (sm.trajectory == q.trajectory || !sm.finished || sm.nodes.empty()) continue;
      const std::int64_t mid = sm.nodes[sm.nodes.size() / 2];
      if (nodes[static_cast<std::size_t>(mid)].submap != static_cast<int>(si)) continue;
      ++stats.loop_candidates;
      cands.push_back({mid, 0.0});
    }
  }
  for (const SlamNode& k : nodes) {
    if (!verifier) break;
    if (k.trajectory == q.trajectory || k.submap < 0 || !submaps[static_cast<std::size_t>(k.submap)].finished) continue;
    ++stats.loop_candidates;
    if (k.descriptor.scalars.empty() || q.descriptor->scalars.empty()) continue;
    const double score = verifier->score(k.descriptor, *q.descriptor);
    if (score < verifier->threshold()) {
      ++stats.verifier_rejected;
      continue;
    }
    cands.push_back({k.id, score});
  }
  std::stable_sort(cands.begin(), cands.end(), [](const LoopCandidate& a, const LoopCandidate& b) { return a.score > b.score; });
  const int max_tries = verifier ? options.loop_max_matches : static_cast<int>(cands.size());
  std::vector<LoopMatch> out = matchCandidates(q, cands, nullptr, options.global_min_score, max_tries);
  stats.global_detections += out.size();
  return out;
}

std::vector<LoopMatch> GraphSlam::Impl::confirmLocal(const std::vector<LoopMatch>& fresh) {
  if (options.loop_confirmations <= 0) return fresh;
  // Drop pending matches whose query node is too old to be confirmed.
  const std::int64_t newest = last_node ? *last_node : 0;
  std::erase_if(pending_local, [&](const LoopMatch& m) { return newest - m.query > options.loop_confirm_window; });
  std::vector<LoopMatch> out;
  for (const LoopMatch& m : fresh) {
    std::vector<std::size_t> agree;
    for (std::size_t i = 0; i < pending_local.size(); ++i) {
      const LoopMatch& o = pending_local[i];
      if (o.query == m.query) continue;  // another match of the same scan is not an independent confirmation
      if (loopMatchesConfirm(m.implied_map_to_local, m.axis_ratio, o.implied_map_to_local, o.axis_ratio, options))
        agree.push_back(i);
    }
    if (static_cast<int>(agree.size()) >= options.loop_confirmations) {
      out.push_back(m);
      for (auto it = agree.rbegin(); it != agree.rend(); ++it) {
        out.push_back(pending_local[*it]);
        pending_local.erase(pending_local.begin() + static_cast<std::ptrdiff_t>(*it));
      }
    } else {
      pending_local.push_back(m);
    }
  }
  return out;
}

bool GraphSlam::Impl::verifyGlobal(const std::vector<LoopMatch>& fresh, std::vector<LoopMatch>& agreeing) {
  // Stüde §3.2.1: a global detection counts only with n_ver further detections whose targets lie within r_ver
  // of its target. 2D reading: the detections must also agree on where the query trajectory sits in the map
  // (implied local->map transform within 0.5 m / 0.2 rad; chosen, see README).
  for (const LoopMatch& m : fresh) {
    agreeing.clear();
    agreeing.push_back(m);
    const Pose2& a = nodes[static_cast<std::size_t>(m.target)].global_pose;
    for (const LoopMatch& o : pending_global) {
      const Pose2& b = nodes[static_cast<std::size_t>(o.target)].global_pose;
      if ((a.t - b.t).norm() > options.r_ver) continue;
      if (!within(between(m.implied_map_to_local, o.implied_map_to_local), kPlacementTranslation, kPlacementRotation))
        continue;
      agreeing.push_back(o);
    }
    if (static_cast<int>(agreeing.size()) >= 1 + options.n_ver) return true;
  }
  // One detection per query: the query's other matches (overlapping submaps of the same place) agree with it by
  // construction and are no independent verification (Stüde: n_ver detected pairs; as confirmLocal).
  if (!fresh.empty()) pending_global.push_back(fresh.front());
  return false;
}

void GraphSlam::Impl::addLoopEdge(std::int64_t node, const LoopMatch& m) {
  SlamEdge e{m.target, node, EdgeKind::kLoop, m.z, m.information, m.score};
  const std::size_t f = graph.addBetween2(e.from, e.to, e.z, e.information);
  graph.setRobustKernel(f, loop_kernel);
  loop_factors.push_back({edges.size(), f, false});
  edges.push_back(e);
  for (auto it = attempts.rbegin(); it != attempts.rend(); ++it)
    if (it->query == node && it->target == m.target) {
      it->accepted = true;
      break;
    }
  ++stats.loops_accepted;
}

int GraphSlam::Impl::searchLoops(std::int64_t id) {
  const auto t0 = Clock::now();
  ++stats.loop_searches;
  SlamNode& n = nodes[static_cast<std::size_t>(id)];
  LoopQuery q;
  q.trajectory = n.trajectory;
  q.stamp = n.stamp;
  q.global_guess = n.global_pose;
  q.local_pose = n.local_pose;
  q.points = &n.matching_points;
  q.descriptor = &n.descriptor;
  q.node = id;
  q.own_submap = n.submap;
  int added = 0;
  if (!linked) {
    // A new session on a loaded map: global search until n_start verified links (Stüde α_min rule: the
    // search stays global while this trajectory is a small part of the working memory).
    std::vector<LoopMatch> fresh = globalSearch(q);
    std::vector<LoopMatch> agreeing;
    if (!fresh.empty() && verifyGlobal(fresh, agreeing)) {
      // Move the whole new trajectory onto the map where the newest detection puts it, then add the
      // agreeing detections as loop edges (each from its own query node).
      map_to_local = agreeing.front().implied_map_to_local;
      for (SlamNode& t : nodes)
        if (t.trajectory == trajectory) {
          t.global_pose = compose(map_to_local, t.local_pose);
          graph.setPose2(t.id, t.global_pose);
        }
      for (const LoopMatch& m : agreeing) addLoopEdge(m.query, m);
      if (std::getenv("CAIRN_SLAM_DEBUG") != nullptr)
        std::fprintf(stderr, "global link node %ld t=%.1f -> (%.2f,%.2f,%.2f) agreeing %zu\n", static_cast<long>(id), n.stamp,
                     nodes[static_cast<std::size_t>(id)].global_pose.t.x(), nodes[static_cast<std::size_t>(id)].global_pose.t.y(),
                     nodes[static_cast<std::size_t>(id)].global_pose.theta, agreeing.size());
      ++links;
      added = 1;
      // Stüde §3.2.1: global search (each link verified by n_ver detections) for the first n_start links and until
      // n_local / n_WM >= α_min. n_local counts the nodes of the graph connected to the current one: after a link
      // into the (single) existing map that is all of them, so the n_start rule decides. (Before, α was the new
      // trajectory's share of all nodes and OR-ed, so a long unlinked trajectory ended the search after one link.)
      if (links >= options.n_start) linked = true;
      pending_global.clear();
      cov_since_loop.setZero();
    }
  } else {
    const double r = searchRadius();
    stats.last_radius = r;
    const std::size_t matches_before = stats.loop_matches;
    for (const LoopMatch& m : confirmLocal(localSearch(q, r, options.verifier_local_threshold))) {
      addLoopEdge(m.query, m);
      ++added;
    }
    if (std::getenv("CAIRN_SLAM_DEBUG") != nullptr)
      std::fprintf(stderr, "node %ld t=%.1f r=%.2f matches=%zu added=%d pose=(%.1f,%.1f)\n", static_cast<long>(id),
                   n.stamp, r, stats.loop_matches - matches_before, added, n.global_pose.t.x(), n.global_pose.t.y());
    if (added > 0) cov_since_loop.setZero();  // Stüde §3.2.1: reset when a loop closure occurs
  }
  stats.loop_time_s += seconds(t0);
  return added;
}

void GraphSlam::Impl::flushPrelinkScans(std::optional<std::int64_t> node) {
  for (const auto& [stamp, local_pose] : prelink_scans) {
    if (node) {
      const SlamNode& n = nodes[static_cast<std::size_t>(*node)];
      records.push_back({stamp, n.id, between(n.local_pose, local_pose)});
      continue;
    }
    const Pose2 pose = compose(map_to_local, local_pose);
    const SlamNode* nearest = nullptr;
    for (const SlamNode& k : nodes)
      if (!nearest || (k.global_pose.t - pose.t).squaredNorm() < (nearest->global_pose.t - pose.t).squaredNorm()) nearest = &k;
    records.push_back({stamp, nearest->id, between(nearest->global_pose, pose)});
  }
  prelink_scans.clear();
}

std::optional<std::int64_t> GraphSlam::Impl::mappedNodeNear(const Pose2& pose, double stamp) const {
  std::optional<std::int64_t> best;
  double best_d2 = options.revisit_radius * options.revisit_radius;
  for (const SlamNode& k : nodes) {
    if (k.trajectory == trajectory && stamp - k.stamp < options.loop_min_time_gap) continue;
    const double d2 = (k.global_pose.t - pose.t).squaredNorm();
    if (d2 > best_d2) continue;
    if (std::abs(normalizeAngle(k.global_pose.theta - pose.theta)) > options.revisit_angle) continue;
    best = k.id;
    best_d2 = d2;
  }
  return best;
}

std::optional<std::int64_t> GraphSlam::Impl::revisitAnchor(const LocalResult& r) const {
  if (options.revisit_radius <= 0.0 || !linked) return std::nullopt;
  return mappedNodeNear(compose(map_to_local, r.local_pose), r.stamp);
}

void GraphSlam::Impl::collectFinishedSubmaps() {
  for (const auto& s : local->takeNewlyFinished()) {
    const auto idx = static_cast<std::size_t>(submap_base + s->index);
    if (idx < submaps.size() && submaps[idx].submap) submaps[idx].finished = true;
  }
  local->releaseFinished();
}

void GraphSlam::Impl::localizeScan(const LocalResult& r, const sim::LaserScan& scan, ScanUpdate& update) {
  // Localization only: the loaded map is not changed; the current scan is matched against it and
  // map_to_local follows the matches.
  matchToMap(r, scan, update);
  collectFinishedSubmaps();
  current_pose = compose(map_to_local, r.local_pose);
  localization_poses.push_back({r.stamp, current_pose});
  reportPose(update);
}

void GraphSlam::Impl::matchToMap(const LocalResult& r, const sim::LaserScan& scan, ScanUpdate& update) {
  if (r.inserted && options.loop_closure) {
    // Prediction: the pose moves with local SLAM; its uncertainty grows by the floor of the graph's
    // consecutive-node edges (odom_sigma_xy / odom_sigma_theta plus 1 % of the distance, addNode()).
    const double moved = localized_at ? (r.local_pose.t - localized_at->t).norm() : 0.0;
    localized_at = r.local_pose;
    const double sxy = options.odom_sigma_xy + 0.01 * moved, sth = options.odom_sigma_theta + 0.01 * moved;
    cov_since_loop.diagonal() += Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth);
    ++stats.loop_searches;
    const auto t0 = Clock::now();
    ScanDescriptor desc;
    try {
      desc = computeDescriptor(scan, descriptor_options);
    } catch (const std::invalid_argument&) {
    }
    LoopQuery q;
    q.trajectory = -1;  // matches every loaded trajectory
    q.stamp = r.stamp;
    q.global_guess = compose(map_to_local, r.local_pose);
    q.local_pose = r.local_pose;
    q.points = &r.matching_points;
    q.descriptor = &desc;
    std::vector<LoopMatch> found;
    bool placed_globally = false;
    if (linked) {
      found = localSearch(q, searchRadius(), options.verifier_local_threshold);
    } else {
      std::vector<LoopMatch> fresh = globalSearch(q);
      std::vector<LoopMatch> agreeing;
      if (!fresh.empty() && verifyGlobal(fresh, agreeing)) {
        pending_global.clear();
        // Localization links on the first verified detection; a mapping session searching without nodes
        // (revisit_link_scans) waits for n_start of them that agree on where the trajectory sits, as the
        // node-based search waits for n_start links, since a wrong link there would map a second copy.
        const LoopMatch newest = agreeing.front();
        prelink_links.push_back(newest);
        std::erase_if(prelink_links, [&](const LoopMatch& o) {
          return !within(between(newest.implied_map_to_local, o.implied_map_to_local), kPlacementTranslation,
                         kPlacementRotation);
        });
        if (options.localization_only || static_cast<int>(prelink_links.size()) >= options.n_start) {
          found.push_back(newest);
          linked = true;
          placed_globally = true;
          prelink_links.clear();
        }
      }
    }
    std::sort(found.begin(), found.end(), [](const LoopMatch& a, const LoopMatch& b) { return a.score > b.score; });
    Pose2 x = q.global_guess;
    for (const LoopMatch& m : found) {
      // The match's covariance, from the query's frame (where LoopMatch::information lives) into the map frame.
      Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
      R.topLeftCorner<2, 2>() = rot(m.implied_query_global.theta);
      const Eigen::Matrix3d sigma_z = R * m.information.inverse() * R.transpose();
      if (!placed_globally) {
        // Kalman update of (x, y, θ) with the match (a corridor's match is weak along its axis, so the
        // prediction holds there); a match that disagrees beyond χ²₃ 99.9 % (16.27) is not taken.
        const Eigen::Matrix3d S = cov_since_loop + sigma_z;
        Eigen::Vector3d y(m.implied_query_global.t.x() - x.t.x(), m.implied_query_global.t.y() - x.t.y(),
                          normalizeAngle(m.implied_query_global.theta - x.theta));
        const Eigen::Matrix3d S_inv = S.inverse();
        if (!(y.dot(S_inv * y) <= 16.27)) {
          ++stats.localization_gated;
          continue;
        }
        const Eigen::Matrix3d K = cov_since_loop * S_inv;
        x = retract(x, K * y);
        cov_since_loop = (Eigen::Matrix3d::Identity() - K) * cov_since_loop;
        cov_since_loop = 0.5 * (cov_since_loop + cov_since_loop.transpose()).eval();
      } else {
        x = m.implied_query_global;  // placed by a verified global search: the prediction meant nothing
        cov_since_loop = sigma_z;
      }
      ++stats.localization_matches;  // not loops_accepted: no edge, so not in the loop precision
      update.loops_added = 1;
    }
    map_to_local = compose(x, inverse(r.local_pose));
    stats.loop_time_s += seconds(t0);
  }
}

Pose2 GraphSlam::Impl::loopResidual(const SlamEdge& e) const {
  return compose(inverse(e.z), between(nodes[static_cast<std::size_t>(e.from)].global_pose,
                                       nodes[static_cast<std::size_t>(e.to)].global_pose));
}

bool GraphSlam::Impl::readmitAgreeingLoops() {
  if (options.loop_readmit_min_set <= 0 || !last_node) return false;
  // Suppressed recent loops: residual χ² of the constraint at the current solution above the threshold.
  auto pose = [&](std::int64_t id) -> const Pose2& { return nodes[static_cast<std::size_t>(id)].global_pose; };
  std::vector<std::size_t> cand;  // indices into loop_factors
  for (std::size_t i = 0; i < loop_factors.size(); ++i) {
    const LoopFactor& lf = loop_factors[i];
    const SlamEdge& e = edges[lf.edge];
    if (lf.readmitted || *last_node - e.to > options.loop_readmit_window) continue;
    const Pose2 err = loopResidual(e);
    const Eigen::Vector3d r(err.t.x(), err.t.y(), normalizeAngle(err.theta));
    if (r.dot(e.information * r) > options.loop_readmit_chi2) cand.push_back(i);
  }
  if (static_cast<int>(cand.size()) < options.loop_readmit_min_set) return false;
  // Pairwise agreement: pose of query j in target i's frame through loop j and the estimated path between the
  // targets, and through loop i and the estimated path between the queries.
  auto agree = [&](std::size_t i, std::size_t j) {
    const SlamEdge& a = edges[loop_factors[i].edge];
    const SlamEdge& b = edges[loop_factors[j].edge];
    const Pose2 via_j = compose(between(pose(a.from), pose(b.from)), b.z);
    const Pose2 via_i = compose(a.z, between(pose(a.to), pose(b.to)));
    return within(between(via_i, via_j), options.loop_confirm_translation, options.loop_confirm_rotation);
  };
  // Largest mutually agreeing set, greedily from each seed (the candidate sets are small: tens of loops).
  std::vector<std::size_t> best;
  for (std::size_t s = 0; s < cand.size(); ++s) {
    std::vector<std::size_t> set{cand[s]};
    for (std::size_t c = 0; c < cand.size(); ++c) {
      if (c == s) continue;
      bool ok = true;
      for (std::size_t m : set) ok = ok && agree(m, cand[c]) && agree(cand[c], m);
      if (ok) set.push_back(cand[c]);
    }
    if (set.size() > best.size()) best = std::move(set);
  }
  if (static_cast<int>(best.size()) < options.loop_readmit_min_set) return false;
  double span = 0.0;
  for (std::size_t i : best)
    for (std::size_t j : best)
      span = std::max(span, (pose(edges[loop_factors[i].edge].to).t - pose(edges[loop_factors[j].edge].to).t).norm());
  if (span < options.loop_readmit_min_span) return false;
  for (std::size_t i : best) {
    graph.setRobustKernel(loop_factors[i].factor, readmit_kernel);
    loop_factors[i].readmitted = true;
  }
  stats.loops_readmitted += best.size();
  return true;
}

OptimizerSummary GraphSlam::Impl::optimize() {
  const auto t0 = Clock::now();
  OptimizerSummary s;
  if (graph.variables().empty()) return s;
  const auto solve = [&] {
    s = optimizer.optimize(graph);
    for (SlamNode& n : nodes) n.global_pose = graph.pose2(n.id);
  };
  solve();
  if (readmitAgreeingLoops()) solve();  // re-admitted loops change the solution: solve again
  if (last_node) {
    const SlamNode& n = nodes[static_cast<std::size_t>(*last_node)];
    map_to_local = compose(n.global_pose, inverse(n.local_pose));
  }
  nodes_since_optimize = 0;
  ++stats.optimizations;
  stats.optimize_time_s += seconds(t0);
  return s;
}

// ---------------------------------------------------------------- GraphSlam

GraphSlam::GraphSlam(SlamOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
GraphSlam::~GraphSlam() = default;
GraphSlam::GraphSlam(GraphSlam&&) noexcept = default;
GraphSlam& GraphSlam::operator=(GraphSlam&&) noexcept = default;

std::optional<ScanUpdate> GraphSlam::addScan(const sim::LaserScan& scan, const std::optional<Pose2>& odom) {
  return impl_->addScan(scan, odom);
}

OptimizerSummary GraphSlam::optimize() { return impl_->optimize(); }

void GraphSlam::setInitialPose(const Pose2& pose) { impl_->initial_pose = pose; }
bool GraphSlam::localized() const { return impl_->linked; }
void GraphSlam::setSensorInBase(const Pose2& sensor_in_base) { impl_->options.sensor_in_base = sensor_in_base; }

void GraphSlam::finish() {
  if (!impl_->options.localization_only) impl_->optimize();
}

std::vector<StampedPose> GraphSlam::trajectory() const {
  std::vector<StampedPose> out;
  out.reserve(impl_->records.size() + impl_->localization_poses.size());
  for (const ScanRecord& r : impl_->records)
    out.push_back({r.stamp, compose(impl_->nodes[static_cast<std::size_t>(r.node)].global_pose, r.relative)});
  out.insert(out.end(), impl_->localization_poses.begin(), impl_->localization_poses.end());
  return out;
}

OccupancyGrid GraphSlam::map() const {
  ProbabilityGrid g(impl_->options.map_resolution, impl_->options.local.grid);
  for (const SlamNode& n : impl_->nodes) g.insert(n.range_data, n.global_pose);
  return toOccupancyGrid(g);
}

Pose2 GraphSlam::currentPose() const { return impl_->current_pose; }
Pose2 GraphSlam::mapToLocal() const { return impl_->map_to_local; }
const std::vector<SlamNode>& GraphSlam::nodes() const { return impl_->nodes; }
const std::vector<SlamSubmap>& GraphSlam::submaps() const { return impl_->submaps; }
const std::vector<SlamEdge>& GraphSlam::edges() const { return impl_->edges; }
const PoseGraph& GraphSlam::graph() const { return impl_->graph; }
const SlamStats& GraphSlam::stats() const { return impl_->stats; }
const SlamOptions& GraphSlam::options() const { return impl_->options; }
const std::string& GraphSlam::lastError() const { return impl_->last_error; }

LoopRecall GraphSlam::loopRecall(double max_distance) const {
  LoopRecall r;
  for (const LoopAttempt& a : impl_->attempts) {
    const auto& q = impl_->nodes[static_cast<std::size_t>(a.query)].global_pose;
    const auto& t = impl_->nodes[static_cast<std::size_t>(a.target)].global_pose;
    if ((q.t - t.t).norm() > max_distance) continue;
    ++r.revisits;
    r.matched += a.matched ? 1 : 0;
    r.accepted += a.accepted ? 1 : 0;
  }
  return r;
}

std::size_t GraphSlam::inconsistentLoops(double max_translation, double max_rotation) const {
  std::size_t bad = 0;
  for (const SlamEdge& e : impl_->edges) {
    if (e.kind != EdgeKind::kLoop) continue;
    if (!within(impl_->loopResidual(e), max_translation, max_rotation)) ++bad;
  }
  return bad;
}

}  // namespace cairn::graph_slam
