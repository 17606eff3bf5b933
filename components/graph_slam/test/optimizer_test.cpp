// Optimizer: known solutions, gauge handling, assembled system vs a dense reference, robust kernels against
// injected outliers, marginal covariances against a dense inverse, incremental re-optimization vs batch.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "cairn/graph_slam/factors.hpp"
#include "cairn/graph_slam/optimizer.hpp"
#include "cairn/graph_slam/pose_graph.hpp"

namespace gs = cairn::graph_slam;

namespace {

// A 2D trajectory on a grid-like loop (ground truth) with odometry and loop closures.
struct Synthetic2d {
  std::vector<gs::Pose2> truth;
  std::vector<std::pair<int, int>> edges;
};

Synthetic2d makeLoop2d(int laps, int per_side) {
  Synthetic2d s;
  gs::Pose2 p;
  for (int lap = 0; lap < laps; ++lap) {
    for (int side = 0; side < 4; ++side) {
      for (int k = 0; k < per_side; ++k) {
        s.truth.push_back(p);
        p = gs::compose(p, gs::Pose2{Eigen::Vector2d(1.0, 0.0), k + 1 == per_side ? M_PI / 2 : 0.0});
      }
    }
  }
  const int n = static_cast<int>(s.truth.size());
  for (int i = 0; i + 1 < n; ++i) s.edges.emplace_back(i, i + 1);
  const int period = 4 * per_side;
  for (int i = period; i < n; i += 2) s.edges.emplace_back(i - period, i);  // revisits
  return s;
}

gs::PoseGraph buildGraph2d(const Synthetic2d& s, double noise, unsigned seed, bool perturb_values,
                           double info_scale = 1.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd(0.0, 1.0);
  gs::PoseGraph g;
  for (std::size_t i = 0; i < s.truth.size(); ++i) {
    gs::Pose2 v = s.truth[i];
    if (perturb_values && i > 0) {
      v.t += Eigen::Vector2d(nd(rng), nd(rng)) * 0.3;
      v.theta += 0.1 * nd(rng);
    }
    g.addPose2(static_cast<gs::VariableId>(i), v);
  }
  Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  info(2, 2) = 10.0;
  info(0, 1) = info(1, 0) = 0.2;
  info *= info_scale;
  for (const auto& [i, j] : s.edges) {
    gs::Pose2 z = gs::compose(gs::inverse(s.truth[i]), s.truth[j]);
    z.t += Eigen::Vector2d(nd(rng), nd(rng)) * noise;
    z.theta += nd(rng) * noise * 0.3;
    g.addBetween2(i, j, z, info);
  }
  return g;
}

gs::PoseGraph buildGraph3d(int n, double noise, unsigned seed, std::vector<gs::Pose3>* truth_out) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd(0.0, 1.0);
  std::vector<gs::Pose3> truth;
  gs::Pose3 p;
  for (int i = 0; i < n; ++i) {
    truth.push_back(p);
    gs::Pose3 step;
    step.t = Eigen::Vector3d(1.0, 0.0, 0.1);
    step.q = gs::expSO3(Eigen::Vector3d(0.05, 0.02, 2.0 * M_PI / 12.0));
    p = gs::compose(p, step);
  }
  gs::PoseGraph g;
  for (int i = 0; i < n; ++i) {
    gs::Pose3 v = truth[i];
    if (i > 0) {
      gs::Vector6d d;
      for (int k = 0; k < 6; ++k) d[k] = nd(rng) * (k < 3 ? 0.2 : 0.05);
      v = gs::retract(v, d);
    }
    g.addPose3(i, v);
  }
  gs::Matrix6d info = gs::Matrix6d::Identity();
  info.bottomRightCorner<3, 3>() *= 20.0;
  info(0, 4) = info(4, 0) = 0.3;
  auto add = [&](int i, int j) {
    gs::Pose3 z = gs::compose(gs::inverse(truth[i]), truth[j]);
    gs::Vector6d d;
    for (int k = 0; k < 6; ++k) d[k] = nd(rng) * noise;
    g.addBetween3(i, j, gs::retract(z, d), info);
  };
  for (int i = 0; i + 1 < n; ++i) add(i, i + 1);
  for (int i = 12; i < n; i += 3) add(i - 12, i);
  if (truth_out) *truth_out = truth;
  return g;
}

double maxPositionError(const gs::PoseGraph& g, const std::vector<gs::Pose2>& truth) {
  double m = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    m = std::max(m, (g.pose2(static_cast<gs::VariableId>(i)).t - truth[i].t).norm());
  }
  return m;
}

}  // namespace

class AllSolvers : public ::testing::TestWithParam<gs::Algorithm> {};

TEST_P(AllSolvers, NoiseFree2dLoopConvergesToTruth) {
  const Synthetic2d s = makeLoop2d(2, 5);
  gs::PoseGraph g = buildGraph2d(s, 0.0, 1, /*perturb_values=*/true);
  ASSERT_GT(g.chi2(), 1.0);
  gs::OptimizerOptions o;
  o.algorithm = GetParam();
  gs::Optimizer opt(o);
  const auto sum = opt.optimize(g);
  EXPECT_TRUE(sum.converged) << sum.termination;
  EXPECT_LT(sum.final_chi2, 1e-12);
  EXPECT_LT(maxPositionError(g, s.truth), 1e-6);
  ASSERT_TRUE(sum.gauge.has_value());
  EXPECT_EQ(*sum.gauge, 0);
}

TEST_P(AllSolvers, NoiseFree3dGraphConvergesToTruth) {
  std::vector<gs::Pose3> truth;
  gs::PoseGraph g = buildGraph3d(40, 0.0, 2, &truth);
  gs::OptimizerOptions o;
  o.algorithm = GetParam();
  gs::Optimizer opt(o);
  const auto sum = opt.optimize(g);
  EXPECT_TRUE(sum.converged) << sum.termination;
  EXPECT_LT(sum.final_chi2, 1e-12);
  for (int i = 0; i < 40; ++i) {
    EXPECT_LT((g.pose3(i).t - truth[i].t).norm(), 1e-6);
    EXPECT_LT(g.pose3(i).q.angularDistance(truth[i].q), 1e-6);
  }
}

INSTANTIATE_TEST_SUITE_P(Optimizer, AllSolvers,
                         ::testing::Values(gs::Algorithm::kLevenbergMarquardt, gs::Algorithm::kGaussNewton,
                                           gs::Algorithm::kDogleg));

TEST(Optimizer, GaugeFollowsFixedVariablesAndPriors) {
  const Synthetic2d s = makeLoop2d(1, 4);
  {
    gs::PoseGraph g = buildGraph2d(s, 0.01, 3, true);
    g.setFixed(5);
    const gs::Pose2 before = g.pose2(5);
    gs::Optimizer opt;
    const auto sum = opt.optimize(g);
    EXPECT_FALSE(sum.gauge.has_value());
    EXPECT_EQ(g.pose2(5).t, before.t);  // fixed variable untouched
    EXPECT_EQ(g.pose2(5).theta, before.theta);
    EXPECT_TRUE(sum.converged);
  }
  {
    gs::PoseGraph g = buildGraph2d(s, 0.01, 3, true);
    g.addPrior2(3, s.truth[3], Eigen::Matrix3d::Identity() * 1e4);
    gs::Optimizer opt;
    const auto sum = opt.optimize(g);
    EXPECT_FALSE(sum.gauge.has_value());
    EXPECT_TRUE(sum.converged) << sum.termination;
    EXPECT_LT((g.pose2(3).t - s.truth[3].t).norm(), 0.05);
  }
}

// One Gauss-Newton step of the optimizer equals the dense step (H = sum J^T Omega J with analytic Jacobians,
// solved densely): checks the block-sparse assembly, the AMD ordering and the CHOLMOD solve together.
TEST(Optimizer, GaussNewtonStepEqualsDenseReference) {
  gs::PoseGraph g;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 6; ++i) g.addPose2(i, gs::Pose2{Eigen::Vector2d(i + 0.1 * u(rng), 0.2 * u(rng)), 0.1 * u(rng)});
  g.addPoint2(100, Eigen::Vector2d(2.0, 2.0));
  g.addPoint2(101, Eigen::Vector2d(4.0, -2.0));
  Eigen::Matrix3d info;
  info << 3, 0.5, 0.1, 0.5, 2, 0.2, 0.1, 0.2, 5;
  for (int i = 0; i < 5; ++i) g.addBetween2(i, i + 1, gs::Pose2{Eigen::Vector2d(1, 0), 0.05}, info);
  g.addBetween2(0, 5, gs::Pose2{Eigen::Vector2d(5, 0.3), 0.2}, info);
  g.addPose2Point2(1, 100, Eigen::Vector2d(1.0, 2.1), Eigen::Matrix2d::Identity() * 2);
  g.addPose2Point2(3, 100, Eigen::Vector2d(-1.0, 2.0), Eigen::Matrix2d::Identity());
  g.addPose2Point2(4, 101, Eigen::Vector2d(0.1, -2.0), Eigen::Matrix2d::Identity());
  g.addPose2Point2(5, 101, Eigen::Vector2d(-1.0, -2.1), Eigen::Matrix2d::Identity());
  g.addPrior2(0, gs::Pose2{}, Eigen::Matrix3d::Identity() * 100);

  // Dense reference: variable order as inserted, all free (the prior fixes the gauge).
  std::vector<int> off;
  int n = 0;
  for (const auto& v : g.variables()) {
    off.push_back(n);
    n += gs::tangentDim(v.kind);
  }
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  const auto& x = g.variables();
  for (const auto& f : g.factors()) {
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(gs::errorDim(f.kind), n);
    Eigen::VectorXd e;
    if (f.kind == gs::FactorKind::kBetween2) {
      Eigen::Matrix3d ja, jb;
      e = gs::errorBetween2(x[f.var[0]].pose2, x[f.var[1]].pose2, f.z2, &ja, &jb);
      j.middleCols(off[f.var[0]], 3) = ja;
      j.middleCols(off[f.var[1]], 3) = jb;
    } else if (f.kind == gs::FactorKind::kPrior2) {
      Eigen::Matrix3d ja;
      e = gs::errorPrior2(x[f.var[0]].pose2, f.z2, &ja);
      j.middleCols(off[f.var[0]], 3) = ja;
    } else {
      Eigen::Matrix<double, 2, 3> ja;
      Eigen::Matrix2d jb;
      e = gs::errorPose2Point2(x[f.var[0]].pose2, x[f.var[1]].point.head<2>(), f.zp.head<2>(), &ja, &jb);
      j.middleCols(off[f.var[0]], 3) = ja;
      j.middleCols(off[f.var[1]], 2) = jb;
    }
    const int d = gs::errorDim(f.kind);
    const Eigen::MatrixXd om = f.information.topLeftCorner(d, d);
    h += j.transpose() * om * j;
    b -= j.transpose() * om * e;
  }
  const Eigen::VectorXd step = h.ldlt().solve(b);

  gs::OptimizerOptions o;
  o.algorithm = gs::Algorithm::kGaussNewton;
  o.max_iterations = 1;
  gs::PoseGraph g2 = g;
  gs::Optimizer(o).optimize(g2);
  for (std::size_t v = 0; v < x.size(); ++v) {
    const auto& a = g2.variables()[v];
    if (a.kind == gs::VariableKind::kPose2) {
      const gs::Pose2 ref = gs::retract(x[v].pose2, Eigen::Vector3d(step.segment<3>(off[v])));
      EXPECT_NEAR(a.pose2.t.x(), ref.t.x(), 1e-9);
      EXPECT_NEAR(a.pose2.t.y(), ref.t.y(), 1e-9);
      EXPECT_NEAR(a.pose2.theta, ref.theta, 1e-9);
    } else {
      EXPECT_TRUE(a.point.head<2>().isApprox(x[v].point.head<2>() + step.segment<2>(off[v]), 1e-9));
    }
  }
}

TEST(Optimizer, RobustKernelsRejectInjectedOutliers) {
  const Synthetic2d s = makeLoop2d(3, 6);
  // Measurement noise 0.02 with sigma = 0.1 (information 100): inliers stay inside the kernels' quadratic zone.
  gs::PoseGraph clean = buildGraph2d(s, 0.02, 9, false, 100.0);
  gs::Optimizer().optimize(clean);
  const double clean_err = maxPositionError(clean, s.truth);

  // Inject 15 false loop closures between random poses, claiming identity-ish relative poses.
  auto corrupt = [&] {
    gs::PoseGraph g = buildGraph2d(s, 0.02, 9, false, 100.0);
    std::mt19937 rng(21);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(s.truth.size()) - 1);
    Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
    info(2, 2) = 10.0;
    info(0, 1) = info(1, 0) = 0.2;
    info *= 100.0;
    for (int k = 0; k < 15; ++k) {
      int i = pick(rng), j = pick(rng);
      if (std::abs(i - j) < 2) continue;
      g.addBetween2(i, j, gs::Pose2{Eigen::Vector2d(0.5, 0.0), 0.3}, info);
    }
    return g;
  };
  gs::PoseGraph plain = corrupt();
  gs::Optimizer().optimize(plain);
  const double plain_err = maxPositionError(plain, s.truth);
  EXPECT_GT(plain_err, 0.5);  // least squares is dragged away by the outliers

  for (const char* k : {"dcs:1", "cauchy:1", "gm:1"}) {
    gs::PoseGraph g = corrupt();
    g.setRobustKernelAll(gs::RobustKernel::parse(k));
    const auto sum = gs::Optimizer().optimize(g);
    EXPECT_TRUE(sum.converged) << k;
    EXPECT_LT(maxPositionError(g, s.truth), clean_err + 0.01) << k;
  }
}

TEST(Optimizer, MarginalCovarianceOfChainEqualsDenseInverse) {
  gs::PoseGraph g;
  Eigen::Matrix3d info;
  info << 20, 1, 0.5, 1, 10, 0.3, 0.5, 0.3, 50;
  for (int i = 0; i < 8; ++i) g.addPose2(i, gs::Pose2{Eigen::Vector2d(i, 0.1 * i), 0.05 * i});
  for (int i = 0; i < 7; ++i) g.addBetween2(i, i + 1, gs::Pose2{Eigen::Vector2d(1, 0.1), 0.05}, info);
  g.addBetween2(0, 7, gs::Pose2{Eigen::Vector2d(7, 0.7), 0.35}, info);
  g.addPrior2(0, gs::Pose2{}, Eigen::Matrix3d::Identity() * 100.0);
  gs::Optimizer opt;
  opt.optimize(g);
  const std::vector<gs::VariableId> ids{3, 7, 0};
  const auto cov = opt.marginalCovariances(g, ids);

  // Dense reference H at the optimum.
  const int n = 24;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  const auto& x = g.variables();
  for (const auto& f : g.factors()) {
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(3, n);
    if (f.kind == gs::FactorKind::kBetween2) {
      Eigen::Matrix3d ja, jb;
      gs::errorBetween2(x[f.var[0]].pose2, x[f.var[1]].pose2, f.z2, &ja, &jb);
      j.middleCols(3 * f.var[0], 3) = ja;
      j.middleCols(3 * f.var[1], 3) = jb;
    } else {
      Eigen::Matrix3d ja;
      gs::errorPrior2(x[f.var[0]].pose2, f.z2, &ja);
      j.middleCols(3 * f.var[0], 3) = ja;
    }
    h += j.transpose() * f.information.topLeftCorner<3, 3>() * j;
  }
  const Eigen::MatrixXd sigma = h.inverse();
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const Eigen::MatrixXd ref = sigma.block<3, 3>(3 * ids[k], 3 * ids[k]);
    EXPECT_LT((cov[k] - ref).norm(), 1e-9 * ref.norm()) << cov[k] << "\n" << ref;
  }
  // The uncertainty grows away from the prior.
  EXPECT_GT(cov[0].determinant(), cov[2].determinant());
}

TEST(Optimizer, IncrementalReoptimizationEqualsBatchAndReusesSymbolicAnalysis) {
  const Synthetic2d s = makeLoop2d(2, 5);
  const gs::PoseGraph full = buildGraph2d(s, 0.03, 17, false);
  gs::PoseGraph batch = full;
  gs::Optimizer batch_opt;
  batch_opt.optimize(batch);

  // Incremental: add poses (initialized by odometry from the current estimate) and factors in order,
  // re-optimizing at every loop closure with one optimizer (warm start).
  gs::PoseGraph inc;
  gs::OptimizerOptions o;
  o.warm_start_damping = true;
  o.incremental_ordering = true;
  gs::Optimizer opt(o);
  int reused = 0, rebuilds = 0;
  inc.addPose2(0, full.pose2(0));
  for (const auto& f : full.factors()) {
    const auto i = full.variables()[f.var[0]].id, j = full.variables()[f.var[1]].id;
    if (!inc.hasVariable(j)) inc.addPose2(j, gs::compose(inc.pose2(i), f.z2));
    inc.addBetween2(i, j, f.z2, f.information.topLeftCorner<3, 3>());
    if (j != i + 1) {
      const auto sum = opt.optimize(inc);
      EXPECT_TRUE(sum.structure_rebuilt);
      EXPECT_TRUE(sum.converged);
      reused += sum.ordering_reused;
      ++rebuilds;
    }
  }
  // Poses were only appended: after the first solve the elimination order is kept (new poses last) unless
  // the fill guard asked for a fresh ordering.
  EXPECT_GE(reused, 1);
  EXPECT_LT(reused, rebuilds);
  const auto final_sum = opt.optimize(inc);
  const int analyses = final_sum.symbolic_analyses;
  // Only values changed since: re-optimizing (even from perturbed values) reuses the symbolic factorization.
  gs::Pose2 p = inc.pose2(7);
  p.t.x() += 0.5;
  inc.setPose2(7, p);
  const auto again = opt.optimize(inc);
  EXPECT_FALSE(again.structure_rebuilt);
  EXPECT_EQ(again.symbolic_analyses, analyses);
  EXPECT_GT(again.numeric_factorizations, final_sum.numeric_factorizations);

  EXPECT_NEAR(again.final_chi2, batch.chi2(), 1e-8 * batch.chi2());
  for (const auto& v : batch.variables()) {
    EXPECT_LT((inc.pose2(v.id).t - v.pose2.t).norm(), 1e-6);
    EXPECT_NEAR(inc.pose2(v.id).theta, v.pose2.theta, 1e-6);
  }
}

TEST(Optimizer, IncrementalOrderingFallsBackToFreshOrderingWhenFillGrows) {
  const Synthetic2d s = makeLoop2d(2, 5);
  const gs::PoseGraph full = buildGraph2d(s, 0.03, 5, false);
  for (const double tolerance : {-1.0, 1e9}) {
    gs::OptimizerOptions o;
    o.incremental_ordering = true;
    o.incremental_fill_tolerance = tolerance;  // -1: every reuse exceeds it; 1e9: never
    gs::Optimizer opt(o);
    gs::PoseGraph inc;
    inc.addPose2(0, full.pose2(0));
    int reused = 0;
    for (const auto& f : full.factors()) {
      const auto i = full.variables()[f.var[0]].id, j = full.variables()[f.var[1]].id;
      if (!inc.hasVariable(j)) inc.addPose2(j, gs::compose(inc.pose2(i), f.z2));
      inc.addBetween2(i, j, f.z2, f.information.topLeftCorner<3, 3>());
      if (j != i + 1) reused += opt.optimize(inc).ordering_reused;
    }
    gs::PoseGraph batch = full;
    gs::Optimizer().optimize(batch);
    EXPECT_NEAR(opt.optimize(inc).final_chi2, batch.chi2(), 1e-8 * batch.chi2());
    if (tolerance < 0.0) {
      EXPECT_EQ(reused, 0);
    } else {
      EXPECT_GT(reused, 0);
    }
  }
}

// Factorization reuse (chord steps), step extension, the dogleg look-ahead and the automatic nested
// dissection ordering change the path, not the minimum: same chi2 as the plain algorithms.
TEST(Optimizer, AccelerationsReachTheSameMinimum) {
  const gs::PoseGraph g3 = buildGraph3d(60, 0.05, 23, nullptr);
  for (const auto alg : {gs::Algorithm::kLevenbergMarquardt, gs::Algorithm::kDogleg}) {
    gs::OptimizerOptions plain;
    plain.algorithm = alg;
    plain.factor_reuse = 0;
    plain.step_extension = 0;
    plain.dogleg_lookahead = 0;
    plain.ordering = gs::Ordering::kAmd;
    gs::OptimizerOptions fast;
    fast.algorithm = alg;
    fast.factor_reuse_min_gain = 0.0;   // reuse even where a factorization is cheap (small test graph)
    fast.nd_min_flops_per_block = 0.0;  // always try nested dissection
    gs::PoseGraph a = g3, b = g3;
    const auto sa = gs::Optimizer(plain).optimize(a);
    const auto sb = gs::Optimizer(fast).optimize(b);
    EXPECT_TRUE(sa.converged) << sa.termination;
    EXPECT_TRUE(sb.converged) << sb.termination;
    EXPECT_EQ(sa.reused_factorizations, 0);
    EXPECT_GT(sb.reused_factorizations, 0);
    EXPECT_NEAR(sb.final_chi2, sa.final_chi2, 1e-7 * sa.final_chi2);
    EXPECT_LT(sb.numeric_factorizations, sb.iterations + 1);
  }
}

TEST(Optimizer, SingularSystemIsDampedNotCrashed) {
  // A point observed by nothing constrains nothing: the Hessian is singular. Every solver must still finish
  // (LM and dogleg damp it; GN's factorization leaves the unconstrained point where it is).
  for (const gs::Algorithm alg : {gs::Algorithm::kLevenbergMarquardt, gs::Algorithm::kGaussNewton, gs::Algorithm::kDogleg}) {
    gs::PoseGraph g;
    g.addPose2(0, {});
    g.addPose2(1, gs::Pose2{Eigen::Vector2d(0.8, 0.1), 0.1});
    g.addPoint2(2, Eigen::Vector2d(3, 3));
    g.addBetween2(0, 1, gs::Pose2{Eigen::Vector2d(1, 0), 0}, Eigen::Matrix3d::Identity());
    gs::OptimizerOptions o;
    o.algorithm = alg;
    const auto sum = gs::Optimizer(o).optimize(g);
    EXPECT_LT(sum.final_chi2, 1e-12) << static_cast<int>(alg) << " " << sum.termination;
    EXPECT_EQ(g.variable(2).point, Eigen::Vector3d(3, 3, 0)) << static_cast<int>(alg);
  }
}

// The replayed simplicial LDL^T factorization (OptimizerOptions::factorization_replay) performs CHOLMOD's own
// floating-point operations in CHOLMOD's order: every solver must give bit-identical iterates with and without it.
namespace {
void expectReplayBitIdentical(const gs::PoseGraph& graph, gs::Algorithm alg, bool singular) {
  gs::OptimizerOptions on, off;
  on.algorithm = off.algorithm = alg;
  off.factorization_replay = false;
  gs::PoseGraph a = graph, b = graph;
  gs::Optimizer oa(on), ob(off);
  const auto sa = oa.optimize(a);
  const auto sb = ob.optimize(b);
  EXPECT_TRUE(sa.factorization_replayed);
  EXPECT_FALSE(sb.factorization_replayed);
  EXPECT_EQ(sa.iterations, sb.iterations);
  EXPECT_EQ(sa.numeric_factorizations, sb.numeric_factorizations);
  EXPECT_EQ(sa.final_chi2, sb.final_chi2);  // exact
  for (std::size_t k = 0; k < a.variables().size(); ++k) {
    EXPECT_EQ(a.variables()[k].pose2.t, b.variables()[k].pose2.t);
    EXPECT_EQ(a.variables()[k].pose2.theta, b.variables()[k].pose2.theta);
    EXPECT_EQ(a.variables()[k].point, b.variables()[k].point);
  }
  const std::vector<gs::VariableId> ids{1, 5};
  if (singular) {
    EXPECT_THROW(oa.marginalCovariances(a, ids), std::runtime_error);
    EXPECT_THROW(ob.marginalCovariances(b, ids), std::runtime_error);
  } else {
    EXPECT_EQ(oa.marginalCovariances(a, ids)[1], ob.marginalCovariances(b, ids)[1]);
  }
}

}  // namespace

TEST(Optimizer, FactorizationReplayIsBitIdenticalToCholmod) {
  const gs::PoseGraph g = buildGraph2d(makeLoop2d(3, 8), 0.05, 31, true);
  for (const auto alg : {gs::Algorithm::kLevenbergMarquardt, gs::Algorithm::kGaussNewton, gs::Algorithm::kDogleg}) {
    expectReplayBitIdentical(g, alg, false);
  }
}

TEST(Optimizer, FactorizationReplayDetectsSingularSystemsLikeCholmod) {
  // Gauss-Newton on a singular Hessian (an unobserved point): the undamped factorization fails at every
  // iteration and the smallest working diagonal shift is added, with and without the replay.
  gs::PoseGraph g = buildGraph2d(makeLoop2d(1, 6), 0.05, 32, true);
  g.addPoint2(1000, Eigen::Vector2d(3, 3));
  expectReplayBitIdentical(g, gs::Algorithm::kGaussNewton, true);
}

TEST(Optimizer, NonFiniteInitialCostIsNotConverged) {
  // Finite values whose chi2 overflows (1e300 m): no step, and not reported as converged.
  for (const gs::Algorithm a : {gs::Algorithm::kLevenbergMarquardt, gs::Algorithm::kGaussNewton, gs::Algorithm::kDogleg}) {
    gs::PoseGraph g;
    g.addPose2(0, gs::Pose2{Eigen::Vector2d(0, 0), 0});
    g.addPose2(1, gs::Pose2{Eigen::Vector2d(1e300, 0), 0});
    g.addBetween2(0, 1, gs::Pose2{Eigen::Vector2d(1, 0), 0}, Eigen::Matrix3d::Identity());
    gs::OptimizerOptions o;
    o.algorithm = a;
    gs::Optimizer opt(o);
    const auto sum = opt.optimize(g);
    EXPECT_FALSE(sum.converged);
    EXPECT_EQ(sum.termination, "initial cost is not finite");
    EXPECT_EQ(sum.iterations, 0);
  }
}
