// Scan filtering, probability grid, correlative / branch-and-bound matching and grid refinement on synthetic
// scans ray-cast into analytic rooms (cairn::sim::castNaive).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Eigenvalues>

#include "cairn/graph_slam/correlative_matcher.hpp"
#include "cairn/graph_slam/grid_refiner.hpp"
#include "cairn/graph_slam/probability_grid.hpp"
#include "cairn/graph_slam/scan_filter.hpp"
#include "cairn/sim/raycast.hpp"

namespace gs = cairn::graph_slam;
namespace sim = cairn::sim;

namespace {

constexpr double kPi = 3.14159265358979323846;

sim::Segment seg(double ax, double ay, double bx, double by) { return {{ax, ay}, {bx, by}, 0.3F}; }

/// An asymmetric 10 x 7 m room with a few boxes and a wall stub (no symmetry, so global search is unique).
std::vector<sim::Segment> room() {
  std::vector<sim::Segment> w = {seg(0, 0, 10, 0), seg(10, 0, 10, 7), seg(10, 7, 0, 7), seg(0, 7, 0, 0),
                                 seg(6, 0, 6, 2.5),  // wall stub
                                 seg(2, 4.5, 3, 4.5), seg(3, 4.5, 3, 5.2), seg(3, 5.2, 2, 5.2), seg(2, 5.2, 2, 4.5),
                                 seg(8, 5, 8.6, 5.8), seg(8.6, 5.8, 8.0, 6.3)};
  return w;
}

/// A 40 m corridor, 2.4 m wide, open at both ends (beyond the laser range from the middle).
std::vector<sim::Segment> corridor() { return {seg(-20, -1.2, 20, -1.2), seg(-20, 1.2, 20, 1.2)}; }

/// Ray-cast scan from base pose `pose` (laser at the base origin), n beams over 360°, Gaussian noise.
sim::LaserScan castScan(const std::vector<sim::Segment>& walls, const gs::Pose2& pose, int n = 360,
                        double noise = 0.0, unsigned seed = 1, double range_max = 20.0) {
  sim::LaserScan s;
  s.angle_min = static_cast<float>(-kPi);
  s.angle_increment = static_cast<float>(2 * kPi / n);
  s.angle_max = static_cast<float>(-kPi + (n - 1) * 2 * kPi / n);
  s.range_min = 0.05F;
  s.range_max = static_cast<float>(range_max);
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd(0.0, noise);
  for (int i = 0; i < n; ++i) {
    const double a = pose.theta + s.angle_min + i * static_cast<double>(s.angle_increment);
    const sim::RayHit h = sim::castNaive(walls, {pose.t.x(), pose.t.y()}, {std::cos(a), std::sin(a)}, range_max);
    s.ranges.push_back(h.hit ? static_cast<float>(h.range + (noise > 0 ? nd(rng) : 0.0))
                             : std::numeric_limits<float>::infinity());
  }
  return s;
}

gs::Pose2 pose2(double x, double y, double th) {
  gs::Pose2 p;
  p.t = {x, y};
  p.theta = th;
  return p;
}

gs::RangeData rangeData(const sim::LaserScan& s) { return gs::toRangeData(s, gs::Pose2{}, gs::ScanFilterOptions{}); }

/// A grid built from several scans of the room taken at known poses.
gs::ProbabilityGrid roomGrid(const std::vector<sim::Segment>& walls, const std::vector<gs::Pose2>& poses) {
  gs::ProbabilityGrid g(0.05);
  unsigned seed = 10;
  for (const auto& p : poses) g.insert(rangeData(castScan(walls, p, 720, 0.005, seed++)), p);
  return g;
}

const std::vector<gs::Pose2>& roomPoses() {
  // A submap's worth of views: 24 poses on a loop through the room.
  static const std::vector<gs::Pose2> p = [] {
    std::vector<gs::Pose2> v;
    for (int i = 0; i < 24; ++i) {
      const double a = 2 * kPi * i / 24;
      v.push_back(pose2(4.5 + 2.5 * std::cos(a), 3.2 + 1.5 * std::sin(a), a + 0.3));
    }
    return v;
  }();
  return p;
}

}  // namespace

TEST(ScanFilter, DropsInvalidBeamsAndTurnsNoReturnsIntoMisses) {
  sim::LaserScan s;
  s.angle_min = 0.0F;
  s.angle_increment = 0.1F;
  s.range_min = 0.05F;
  s.range_max = 20.0F;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  s.ranges = {1.0F, nan, inf, 0.0F, -1.0F, -inf, 0.06F, 20.0F, 25.0F, 2.0F};
  gs::ScanFilterOptions o;  // min_range 0.1, max_range 30
  gs::ScanFilterStats st;
  const gs::Pose2 mount = pose2(0.2, 0.0, 0.0);
  const gs::RangeData d = gs::toRangeData(s, mount, o, &st);
  ASSERT_EQ(d.returns.size(), 2U);  // 1.0 and 2.0
  EXPECT_NEAR(d.returns[0].x(), 1.2, 1e-9);
  EXPECT_NEAR(d.returns[1].norm(), (Eigen::Vector2d(0.2, 0) + 2.0 * Eigen::Vector2d(std::cos(0.9), std::sin(0.9))).norm(), 1e-6);
  EXPECT_EQ(d.misses.size(), 3U);  // inf, 20 (= range_max: no return), 25 (>= range_max)
  for (const auto& m : d.misses) EXPECT_NEAR((m - mount.t).norm(), o.miss_range, 1e-9);
  EXPECT_EQ(st.invalid, 4);       // NaN, 0, -1, -inf
  EXPECT_EQ(st.out_of_range, 1);  // 0.06 < min_range
  EXPECT_EQ(d.origin, mount.t);

  o.miss_range = 0.0;  // misses disabled
  EXPECT_TRUE(gs::toRangeData(s, mount, o).misses.empty());
  sim::LaserScan empty;
  EXPECT_TRUE(gs::toRangeData(empty, mount, o).returns.empty());
  s.angle_increment = nan;  // malformed: nothing, no crash
  EXPECT_TRUE(gs::toRangeData(s, mount, o).returns.empty());
}

TEST(ScanFilter, VoxelFilterKeepsOnePointPerVoxelAndAdaptiveKeepsEnough) {
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i < 1000; ++i) pts.emplace_back(0.001 * i, 0.0);  // 1 m line, 1 mm apart
  const auto v = gs::voxelFilter(pts, 0.1);
  EXPECT_EQ(v.size(), 10U);
  EXPECT_EQ(v[0], pts[0]);
  EXPECT_EQ(gs::voxelFilter(pts, 0.0).size(), pts.size());

  const sim::LaserScan s = castScan(room(), pose2(4, 3.5, 0), 720);
  const gs::RangeData d = rangeData(s);
  gs::ScanFilterOptions o;
  const auto a = gs::adaptiveVoxelFilter(d.returns, o);
  EXPECT_GE(a.size(), static_cast<std::size_t>(o.min_points));
  EXPECT_LT(a.size(), d.returns.size());
  // The largest voxel that keeps min_points: a 10 % larger one would keep fewer (bisection to ratio 1.1).
  o.min_points = 5000;  // more than there are: all points
  EXPECT_EQ(gs::adaptiveVoxelFilter(d.returns, o).size(), d.returns.size());
}

TEST(ProbabilityGrid, HitsMissesUnknownAndGrowth) {
  gs::ProbabilityGrid g(0.05);
  gs::RangeData d;
  d.returns = {{2.0, 0.0}};
  d.misses = {{0.0, 3.0}};
  g.insert(d, gs::Pose2{});
  EXPECT_NEAR(g.probability(Eigen::Vector2d(2.01, 0.01)), 0.55, 1e-6);  // first hit: p_hit
  EXPECT_NEAR(g.probability(Eigen::Vector2d(1.0, 0.01)), 0.49, 1e-6);   // crossed: p_miss
  EXPECT_NEAR(g.probability(Eigen::Vector2d(0.01, 2.99)), 0.49, 1e-6);  // miss ray end
  EXPECT_TRUE(g.known(Eigen::Vector2d(1.0, 0.01)));
  EXPECT_FALSE(g.known(Eigen::Vector2d(1.0, 1.0)));
  EXPECT_EQ(g.probability(Eigen::Vector2d(1.0, 1.0)), gs::ProbabilityGrid::kUnknownProbability);
  EXPECT_EQ(g.probability(Eigen::Vector2d(100.0, 100.0)), gs::ProbabilityGrid::kUnknownProbability);
  EXPECT_FLOAT_EQ(g.matchValue(-5, -5), 0.1F);  // outside: p_min for matching
  for (int i = 0; i < 100; ++i) g.insert(d, gs::Pose2{});
  EXPECT_NEAR(g.probability(Eigen::Vector2d(2.01, 0.01)), 0.9, 1e-6);  // clamped at p_max
  EXPECT_NEAR(g.probability(Eigen::Vector2d(1.0, 0.01)), 0.1, 1e-6);   // clamped at p_min
  // Growth keeps existing cells in place.
  const int w0 = g.width();
  g.insert(d, pose2(-20, 15, 0.5));
  EXPECT_GT(g.width(), w0);
  EXPECT_NEAR(g.probability(Eigen::Vector2d(2.01, 0.01)), 0.9, 1e-6);
  const Eigen::Vector2d far = pose2(-20, 15, 0.5).t + gs::rotation2(0.5) * Eigen::Vector2d(2.0, 0.0);
  EXPECT_NEAR(g.probability(far), 0.55, 1e-6);
  gs::CellIndex lo, hi;
  ASSERT_TRUE(g.knownBounds(lo, hi));
  const std::size_t known = g.knownCells();
  g.crop();
  EXPECT_EQ(g.knownCells(), known);
  EXPECT_EQ(g.width(), hi.x - lo.x + 1);
  EXPECT_NEAR(g.probability(Eigen::Vector2d(2.01, 0.01)), 0.9, 1e-6);
  EXPECT_THROW(gs::ProbabilityGrid(0.0), std::invalid_argument);
}

TEST(ProbabilityGrid, BicubicGradientMatchesNumeric) {
  const gs::ProbabilityGrid g = roomGrid(room(), roomPoses());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0.5, 9.5), uy(0.5, 6.5);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d p(ux(rng), uy(rng));
    Eigen::Vector2d grad;
    g.interpolate(p, &grad);
    const double h = 1e-6;
    const double nx = (g.interpolate(p + Eigen::Vector2d(h, 0)) - g.interpolate(p - Eigen::Vector2d(h, 0))) / (2 * h);
    const double ny = (g.interpolate(p + Eigen::Vector2d(0, h)) - g.interpolate(p - Eigen::Vector2d(0, h))) / (2 * h);
    EXPECT_NEAR(grad.x(), nx, 1e-4 * (1 + std::abs(nx)));
    EXPECT_NEAR(grad.y(), ny, 1e-4 * (1 + std::abs(ny)));
  }
  // Interpolation reproduces cell values at cell centres.
  const Eigen::Vector2d c = g.cellCenter(40, 30);
  EXPECT_NEAR(g.interpolate(c), g.matchValue(40, 30), 1e-6);
}

TEST(CorrelativeMatcher, RecoversKnownOffsetWithinOneCellAndStep) {
  const auto walls = room();
  const gs::ProbabilityGrid g = roomGrid(walls, roomPoses());
  const gs::ScanFilterOptions fo;
  const gs::Pose2 truths[] = {pose2(4.3, 3.2, 0.3), pose2(7.0, 4.0, -2.0), pose2(3.5, 1.5, 1.4)};
  const gs::Pose2 offsets[] = {pose2(0.11, -0.07, 0.15), pose2(-0.09, 0.12, -0.25), pose2(0.04, 0.1, 0.3)};
  for (int k = 0; k < 3; ++k) {
    const gs::Pose2 truth = truths[k];
    const gs::RangeData d = rangeData(castScan(walls, truth, 360, 0.01, 20 + k));
    const auto pts = gs::adaptiveVoxelFilter(d.returns, fo);
    const gs::Pose2 initial = gs::compose(truth, offsets[k]);
    gs::SearchWindow w;  // +-0.15 m, +-0.35 rad
    const auto m = gs::correlativeMatch(g, pts, initial, w, 0.3);
    ASSERT_TRUE(m) << k;
    double maxr = 0;
    for (const auto& p : pts) maxr = std::max(maxr, p.norm());
    EXPECT_LE((m->pose.t - truth.t).cwiseAbs().maxCoeff(), 0.05 + 1e-9) << k;
    // One step, plus half a step: the optimum of the discretized search can sit one step beside the truth.
    EXPECT_LE(std::abs(gs::normalizeAngle(m->pose.theta - truth.theta)), 1.5 * gs::angularSearchStep(maxr, 0.05)) << k;
    EXPECT_GT(m->score, 0.6);
  }
  // Nothing to match / too strict: nullopt, no crash.
  EXPECT_FALSE(gs::correlativeMatch(g, {}, truths[0], gs::SearchWindow{}, 0.0));
  EXPECT_FALSE(gs::correlativeMatch(g, {{1.0, 0.0}}, truths[0], gs::SearchWindow{}, 0.999));
  EXPECT_FALSE(gs::correlativeMatch(gs::ProbabilityGrid(0.05), {{1.0, 0.0}}, truths[0], gs::SearchWindow{}, 0.0));
}

TEST(GridRefiner, RefinesToWithinOneCentimetreAndSmallAngle) {
  const auto walls = room();
  const gs::ProbabilityGrid g = roomGrid(walls, roomPoses());
  const gs::ScanFilterOptions fo;
  gs::RefineOptions ro;
  ro.translation_weight = 0.1;  // weak prior: this test is about the grid term
  ro.rotation_weight = 0.1;
  const gs::Pose2 truths[] = {pose2(4.3, 3.2, 0.3), pose2(7.0, 4.0, -2.0), pose2(3.5, 1.5, 1.4), pose2(1.5, 5.8, 3.0)};
  double sum_err = 0;
  for (int k = 0; k < 4; ++k) {
    const gs::Pose2 truth = truths[k];
    const auto pts = gs::adaptiveVoxelFilter(rangeData(castScan(walls, truth, 360, 0.01, 40 + k)).returns, fo);
    // Start one cell and ~one angular step off, as after the correlative matcher.
    const gs::Pose2 initial = gs::compose(truth, pose2(0.04, -0.03, 0.01));
    const gs::RefineResult r = gs::refine(g, pts, initial, initial, ro);
    const double e = (r.pose.t - truth.t).norm();
    sum_err += e;
    EXPECT_LT(e, 0.015) << k;  // each within 1.5 cm, on average within 1 cm (below)
    EXPECT_LT(std::abs(gs::normalizeAngle(r.pose.theta - truth.theta)), 0.3 * kPi / 180) << k;
    EXPECT_GT(r.score, 0.6);
    // Positive definite covariance.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(r.covariance);
    EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
    EXPECT_LT(r.covariance(0, 0), 0.01);
    EXPECT_LT(r.covariance(1, 1), 0.01);
    EXPECT_TRUE(r.converged) << k;
  }
  EXPECT_LT(sum_err / 4, 0.01);
  // The motion prior pulls towards `prior`.
  const auto pts = gs::adaptiveVoxelFilter(rangeData(castScan(walls, truths[0], 360, 0.0, 1)).returns, fo);
  gs::RefineOptions strong;
  strong.translation_weight = 1e4;
  strong.rotation_weight = 1e4;
  const gs::Pose2 prior = gs::compose(truths[0], pose2(0.05, 0.0, 0.0));
  EXPECT_LT((gs::refine(g, pts, truths[0], prior, strong).pose.t - prior.t).norm(), 0.002);
  // No points: the prior back, not converged.
  const auto none = gs::refine(g, {}, truths[0], prior, ro);
  EXPECT_FALSE(none.converged);
  EXPECT_EQ(none.pose.t, prior.t);
}

TEST(GridRefiner, CovarianceIsLargerAlongAFeaturelessCorridor) {
  const auto walls = corridor();
  gs::ProbabilityGrid g(0.05);
  gs::ScanFilterOptions fo;
  fo.max_range = 10.0;  // the corridor ends are out of range: no feature along x
  for (int i = 0; i < 5; ++i) {
    const gs::Pose2 p = pose2(-1.0 + 0.5 * i, 0.1 * (i % 2), 0.05 * i);
    g.insert(gs::toRangeData(castScan(walls, p, 360, 0.005, 60 + i), gs::Pose2{}, fo), p);
  }
  const gs::Pose2 truth = pose2(0.3, 0.05, 0.1);
  const auto pts = gs::adaptiveVoxelFilter(gs::toRangeData(castScan(walls, truth, 360, 0.01, 70), gs::Pose2{}, fo).returns, fo);
  gs::RefineOptions ro;
  const gs::RefineResult r = gs::refine(g, pts, truth, truth, ro);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(r.covariance);
  EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
  EXPECT_GT(r.covariance(0, 0), 100.0 * r.covariance(1, 1));  // along the corridor vs across it
  EXPECT_LT(std::sqrt(r.covariance(1, 1)), 0.05);

  // The room constrains both axes comparably.
  const gs::ProbabilityGrid rg = roomGrid(room(), roomPoses());
  const auto rp = gs::adaptiveVoxelFilter(rangeData(castScan(room(), pose2(4.3, 3.2, 0.3), 360, 0.01, 71)).returns, gs::ScanFilterOptions{});
  const gs::RefineResult rr = gs::refine(rg, rp, pose2(4.3, 3.2, 0.3), pose2(4.3, 3.2, 0.3), ro);
  EXPECT_LT(rr.covariance(0, 0), 10.0 * rr.covariance(1, 1));
  EXPECT_LT(rr.covariance(1, 1), 10.0 * rr.covariance(0, 0));
}

TEST(GridRefiner, DegeneracyAwarePriorHoldsTheCorridorAxisAndLetsTheScanFixTheRest) {
  // A featureless corridor: along x only the prior can place the scan; across it the walls can. A prior that is
  // wrong by 0.2 m along and 0.06 m across: with a weak uniform prior the result follows the walls across the corridor (good)
  // but is free to drift along it; the degeneracy-aware prior (weak across, strong along) keeps x at the prior
  // while still correcting y from the walls.
  const auto walls = corridor();
  gs::ProbabilityGrid g(0.05);
  gs::ScanFilterOptions fo;
  fo.max_range = 10.0;
  for (int i = 0; i < 5; ++i) {
    const gs::Pose2 p = pose2(-1.0 + 0.5 * i, 0.1 * (i % 2), 0.05 * i);
    g.insert(gs::toRangeData(castScan(walls, p, 360, 0.005, 80 + i), gs::Pose2{}, fo), p);
  }
  const gs::Pose2 truth = pose2(0.3, 0.05, 0.1);
  const auto pts = gs::adaptiveVoxelFilter(gs::toRangeData(castScan(walls, truth, 360, 0.01, 90), gs::Pose2{}, fo).returns, fo);
  const gs::Pose2 prior = pose2(0.5, 0.11, 0.1);  // 0.2 m off along, 0.06 m across (inside the grid's basin)
  gs::RefineOptions ro;
  ro.translation_weight = 0.5;
  ro.degenerate_translation_weight = 10.0;
  const gs::RefineResult r = gs::refine(g, pts, prior, prior, ro);
  EXPECT_NEAR(r.pose.t.y(), truth.t.y(), 0.02);  // across: the scan wins over the prior error
  EXPECT_NEAR(r.pose.t.x(), prior.t.x(), 0.02);  // along: held by the strong prior
  // The uniform strong prior (disabled degeneracy term) holds y near the wrong prior too.
  gs::RefineOptions strong;
  strong.translation_weight = 10.0;
  const gs::RefineResult s = gs::refine(g, pts, prior, prior, strong);
  EXPECT_GT(std::abs(s.pose.t.y() - truth.t.y()), std::abs(r.pose.t.y() - truth.t.y()) + 0.01);
}

TEST(BranchAndBound, SameOptimumAsExhaustiveSearch) {
  const auto walls = room();
  const gs::ProbabilityGrid g = roomGrid(walls, roomPoses());
  const gs::BranchAndBoundMatcher bnb(g, 5);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(1.0, 9.0), uy(1.0, 6.0), ut(-kPi, kPi), off(-0.4, 0.4), offa(-0.2, 0.2);
  gs::SearchWindow w;
  w.linear = 0.5;
  w.angular = 0.2;
  w.max_step_range = 3.0;  // coarser angular step: keeps the exhaustive search fast
  for (int k = 0; k < 8; ++k) {
    const gs::Pose2 truth = pose2(ux(rng), uy(rng), ut(rng));
    const auto pts = gs::adaptiveVoxelFilter(rangeData(castScan(walls, truth, 180, 0.02, 80 + k)).returns, gs::ScanFilterOptions{});
    const gs::Pose2 initial = gs::compose(truth, pose2(off(rng), off(rng), offa(rng)));
    const auto brute = gs::correlativeMatch(g, pts, initial, w, 0.0);
    const auto fast = bnb.match(pts, initial, w, 0.0);
    ASSERT_TRUE(brute && fast) << k;
    EXPECT_NEAR(fast->score, brute->score, 1e-6) << k;
    EXPECT_LT(bnb.lastScoredCandidates(), 200000U);
    // min_score above the optimum: nothing.
    EXPECT_FALSE(bnb.match(pts, initial, w, brute->score + 1e-3)) << k;
  }
}

TEST(BranchAndBound, FullSearchFindsThePoseFromAWrongGuess) {
  const auto walls = room();
  const gs::ProbabilityGrid g = roomGrid(walls, roomPoses());
  const gs::BranchAndBoundMatcher bnb(g, 7);
  const gs::Pose2 truths[] = {pose2(7.5, 1.2, 2.5), pose2(1.2, 6.0, -0.7)};
  for (int k = 0; k < 2; ++k) {
    const auto pts = gs::adaptiveVoxelFilter(rangeData(castScan(walls, truths[k], 360, 0.01, 90 + k)).returns, gs::ScanFilterOptions{});
    const auto m = bnb.matchFull(pts, 0.5);
    ASSERT_TRUE(m) << k;
    EXPECT_LT((m->pose.t - truths[k].t).norm(), 0.1) << k;
    EXPECT_LT(std::abs(gs::normalizeAngle(m->pose.theta - truths[k].theta)), 0.05) << k;
    // And refinement from there lands on the truth.
    const auto r = gs::refine(g, pts, m->pose, m->pose, gs::RefineOptions{});
    EXPECT_LT((r.pose.t - truths[k].t).norm(), 0.02) << k;
  }
  EXPECT_FALSE(bnb.matchFull({}, 0.0));
}
