// SE-Sync verification certificate: noise-free and mildly noisy graphs are certified globally optimal; a
// critical point that is not the global minimum (a ring whose rotations wind once too often) is not, with a
// clearly negative lambda_min; 2D and 3D; bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "cairn/graph_slam/certificate.hpp"
#include "cairn/graph_slam/initialization.hpp"
#include "cairn/graph_slam/optimizer.hpp"
#include "cairn/graph_slam/pose_graph.hpp"

namespace gs = cairn::graph_slam;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Poses on a circle of radius 5 facing along it; edges i -> i+1 (closing the ring) and chords i -> i+3 every
// third pose. twist > 0 adds twist extra turns to the headings of the stored values (a start in another basin).
std::vector<gs::Pose2> ringTruth2d(int n) {
  std::vector<gs::Pose2> t;
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * kPi * i / n;
    t.push_back(gs::Pose2{Eigen::Vector2d(5.0 * std::cos(phi), 5.0 * std::sin(phi)), gs::normalizeAngle(phi + kPi / 2)});
  }
  return t;
}

gs::PoseGraph ring2d(int n, bool chords, double noise, int twist, double value_noise, unsigned seed) {
  const auto truth = ringTruth2d(n);
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd;
  gs::PoseGraph g;
  for (int i = 0; i < n; ++i) {
    gs::Pose2 v = truth[i];
    v.theta = gs::normalizeAngle(v.theta + twist * 2.0 * kPi * i / n);
    if (i > 0) {
      v.t += value_noise * Eigen::Vector2d(nd(rng), nd(rng));
      v.theta = gs::normalizeAngle(v.theta + value_noise * nd(rng));
    }
    g.addPose2(i, v);
  }
  Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  info(2, 2) = 20.0;
  auto edge = [&](int i, int j) {
    gs::Pose2 z = gs::compose(gs::inverse(truth[i]), truth[j]);
    z.t += noise * Eigen::Vector2d(nd(rng), nd(rng));
    z.theta = gs::normalizeAngle(z.theta + 0.3 * noise * nd(rng));
    g.addBetween2(i, j, z, info);
  };
  for (int i = 0; i < n; ++i) edge(i, (i + 1) % n);
  if (chords) {
    for (int i = 0; i < n; i += 3) edge(i, (i + 3) % n);
  }
  return g;
}

// The same ring in 3D (xy plane, rotations about z), optionally tilted out of the plane by a helix.
gs::PoseGraph ring3d(int n, bool chords, double noise, int twist, double value_noise, unsigned seed) {
  std::vector<gs::Pose3> truth;
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * kPi * i / n;
    gs::Pose3 p;
    p.t = Eigen::Vector3d(5.0 * std::cos(phi), 5.0 * std::sin(phi), 0.5 * std::sin(2.0 * phi));
    p.q = Eigen::Quaterniond(Eigen::AngleAxisd(phi + kPi / 2, Eigen::Vector3d::UnitZ()));
    truth.push_back(p);
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd;
  gs::PoseGraph g;
  for (int i = 0; i < n; ++i) {
    gs::Pose3 v = truth[i];
    v.q = Eigen::Quaterniond(Eigen::AngleAxisd(twist * 2.0 * kPi * i / n, Eigen::Vector3d::UnitZ())) * v.q;
    if (i > 0) {
      v.t += value_noise * Eigen::Vector3d(nd(rng), nd(rng), nd(rng));
      v.q = v.q * gs::expSO3(value_noise * Eigen::Vector3d(nd(rng), nd(rng), nd(rng)));
    }
    g.addPose3(i, v);
  }
  gs::Matrix6d info = gs::Matrix6d::Identity();
  info.bottomRightCorner<3, 3>() *= 20.0;
  auto edge = [&](int i, int j) {
    gs::Pose3 z = gs::compose(gs::inverse(truth[i]), truth[j]);
    z.t += noise * Eigen::Vector3d(nd(rng), nd(rng), nd(rng));
    z.q = z.q * gs::expSO3(0.3 * noise * Eigen::Vector3d(nd(rng), nd(rng), nd(rng)));
    g.addBetween3(i, j, z, info);
  };
  for (int i = 0; i < n; ++i) edge(i, (i + 1) % n);
  if (chords) {
    for (int i = 0; i < n; i += 3) edge(i, (i + 3) % n);
  }
  return g;
}

// cairn's solution of a mildly noisy graph from chordal initialization: certified after refinement.
gs::CertificateResult certifyOptimizerSolution(gs::PoseGraph g) {
  gs::initializeChordal(g);
  gs::Optimizer().optimize(g);
  const gs::CertificateResult r = gs::certifyGlobalOptimum(g);
  EXPECT_TRUE(r.certified);
  EXPECT_GT(r.objective, 1e-4);                      // noisy: f* > 0
  EXPECT_LE(r.objective, r.objective_input);         // refinement is monotone
  EXPECT_LT(r.objective, 1.05 * r.objective_input);  // cairn's chi2 minimizer is close to f's
  EXPECT_LT(r.stationarity, 1e-8);
  EXPECT_GT(r.lambda_deflated, 0.0);
  return r;
}

// A converged critical point far above f* = 0 (noise-free graph) that the certificate rejects.
void expectRejectedCriticalPoint(const gs::CertificateResult& r) {
  EXPECT_GT(r.objective, 1.0);
  EXPECT_TRUE(r.refine_converged);
  EXPECT_LT(r.gradient_norm, 1e-6 * std::sqrt(r.objective));
  EXPECT_FALSE(r.certified);
  EXPECT_LT(r.lambda_min_upper, -r.eta);
}

}  // namespace

TEST(Certificate, SeSyncObjectiveMatchesDefinition) {
  gs::PoseGraph g;
  g.addPose2(0, gs::Pose2{Eigen::Vector2d(0, 0), 0.0});
  g.addPose2(1, gs::Pose2{Eigen::Vector2d(1, 0.5), 0.3});
  Eigen::Matrix3d info;
  info << 4, 1, 0, 1, 2, 0, 0, 0, 9;
  g.addBetween2(0, 1, gs::Pose2{Eigen::Vector2d(1, 0), 0.1}, info);
  const gs::SeSyncWeights w = gs::seSyncWeights(g.factors()[0]);
  EXPECT_DOUBLE_EQ(w.kappa, 9.0);
  const Eigen::Matrix2d cov_t = info.topLeftCorner<2, 2>().inverse();
  EXPECT_NEAR(w.tau, 2.0 / cov_t.trace(), 1e-15);
  // kappa |R(0.3) - R(0.1)|_F^2 + tau |t1 - t0 - R0 tz|^2 = kappa * 8 sin^2(0.1) + tau * 0.25.
  EXPECT_NEAR(gs::seSyncObjective(g), w.kappa * 8.0 * std::pow(std::sin(0.1), 2) + w.tau * 0.25, 1e-12);
}

TEST(Certificate, NoiseFree2dIsCertified) {
  const gs::PoseGraph g = ring2d(24, true, 0.0, 0, 0.2, 1);
  gs::PoseGraph refined;
  const gs::CertificateResult r = gs::certifyGlobalOptimum(g, {}, &refined);
  EXPECT_EQ(r.dimension, 2);
  EXPECT_EQ(r.poses, 24u);
  EXPECT_GT(r.objective_input, 1.0);
  EXPECT_LT(r.objective, 1e-12);
  EXPECT_TRUE(r.refine_converged);
  EXPECT_TRUE(r.certified);
  EXPECT_GE(r.lambda_min, -r.eta);
  EXPECT_GE(r.lambda_min_lower, -r.eta);
  EXPECT_LE(r.lambda_min_lower, r.lambda_min_upper);
  EXPECT_LE(r.dual_bound_slack, r.eta * 1e6);
  EXPECT_GT(r.lambda_deflated, 0.0);  // strict: only the known null space at zero
  EXPECT_NEAR(gs::seSyncObjective(refined), r.objective, 1e-12);
}

TEST(Certificate, Noisy2dSolutionOfTheOptimizerIsCertified) {
  const gs::CertificateResult r = certifyOptimizerSolution(ring2d(40, true, 0.05, 0, 0.0, 2));
  EXPECT_NEAR(r.dual_bound, r.objective, 1e-8 * r.objective);  // zero duality gap at the certified optimum
}

TEST(Certificate, DualBoundHoldsShortOfACriticalPoint) {
  // Two LM solves from a perturbed noisy start: not yet critical, but where S ⪰ 0 the dual bound is below the
  // optimum reached by the full refinement.
  const gs::PoseGraph g = ring2d(40, true, 0.05, 0, 0.05, 9);
  gs::CertificateOptions few;
  few.max_iterations = 2;
  const gs::CertificateResult partial = gs::certifyGlobalOptimum(g, few);
  const gs::CertificateResult full = gs::certifyGlobalOptimum(g);
  ASSERT_TRUE(full.certified);
  EXPECT_FALSE(partial.refine_converged);
  EXPECT_GT(partial.objective, full.objective);
  EXPECT_TRUE(partial.certified) << partial.lambda_min;
  EXPECT_LE(partial.dual_bound, full.objective);
  EXPECT_LT(partial.dual_bound, partial.objective);
}

TEST(Certificate, TwistedRing2dIsACriticalPointButNotCertified) {
  // Headings wound once more than the measurements imply: LM on f stays in that basin and stops at a critical
  // point with f >> 0, while the noise-free ring has f* = 0; the certificate must reject it.
  const gs::PoseGraph g = ring2d(16, false, 0.0, 1, 0.0, 3);
  const gs::CertificateResult r = gs::certifyGlobalOptimum(g);
  expectRejectedCriticalPoint(r);
  EXPECT_LE(r.lambda_min_lower, r.lambda_min);
  EXPECT_LE(r.lambda_min, r.lambda_min_upper);
  EXPECT_LT(r.lambda_min_upper - r.lambda_min_lower, 2e-3 * std::abs(r.lambda_min_lower));
  // From the true values the same graph is certified at f = 0.
  const gs::CertificateResult ok = gs::certifyGlobalOptimum(ring2d(16, false, 0.0, 0, 0.0, 3));
  EXPECT_TRUE(ok.certified);
  EXPECT_LT(ok.objective, 1e-12);
}

TEST(Certificate, NoiseFree3dIsCertified) {
  const gs::PoseGraph g = ring3d(24, true, 0.0, 0, 0.1, 4);
  const gs::CertificateResult r = gs::certifyGlobalOptimum(g);
  EXPECT_EQ(r.dimension, 3);
  EXPECT_LT(r.objective, 1e-12);
  EXPECT_TRUE(r.certified);
  EXPECT_GT(r.lambda_deflated, 0.0);
}

TEST(Certificate, Noisy3dSolutionOfTheOptimizerIsCertified) {
  certifyOptimizerSolution(ring3d(30, true, 0.05, 0, 0.0, 5));
}

TEST(Certificate, TwistedRing3dIsNotCertified) {
  expectRejectedCriticalPoint(gs::certifyGlobalOptimum(ring3d(16, false, 0.0, 1, 0.0, 6)));
}

TEST(Certificate, WithoutRefinementANonCriticalPointIsNotCertified) {
  // The certificate presumes a critical point: far from one, S = M - Lambda(Y) is not PSD.
  gs::CertificateOptions o;
  o.refine = false;
  const gs::CertificateResult r = gs::certifyGlobalOptimum(ring2d(24, true, 0.0, 0, 0.3, 7), o);
  EXPECT_EQ(r.refine_iterations, 0);
  EXPECT_FALSE(r.certified);
}

TEST(Certificate, RejectsUnsupportedGraphs) {
  gs::PoseGraph empty;
  EXPECT_THROW(gs::certifyGlobalOptimum(empty), std::invalid_argument);
  gs::PoseGraph prior = ring2d(6, false, 0.0, 0, 0.0, 8);
  prior.addPrior2(0, gs::Pose2{}, Eigen::Matrix3d::Identity());
  EXPECT_THROW(gs::certifyGlobalOptimum(prior), std::invalid_argument);
  gs::PoseGraph landmark = ring2d(6, false, 0.0, 0, 0.0, 8);
  landmark.addPoint2(100, Eigen::Vector2d(1, 1));
  EXPECT_THROW(gs::seSyncObjective(landmark), std::invalid_argument);
}
