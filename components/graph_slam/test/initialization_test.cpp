// Odometry (spanning tree) and chordal initialization, 2D and 3D; solver agreement on the Intel data set.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cairn/graph_slam/g2o_io.hpp"
#include "cairn/graph_slam/initialization.hpp"
#include "cairn/graph_slam/optimizer.hpp"

namespace gs = cairn::graph_slam;

namespace {

const std::string kData = std::string(CAIRN_SOURCE_ROOT) + "/test/data/pose_graph/";

// Noise-free graphs (measurements consistent with the truth) whose stored values are garbage.
gs::PoseGraph garbage2d(std::vector<gs::Pose2>& truth) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  gs::Pose2 p;
  for (int i = 0; i < 60; ++i) {
    truth.push_back(p);
    p = gs::compose(p, gs::Pose2{Eigen::Vector2d(1.0, 0.2), 0.3 + 0.1 * std::sin(i)});
  }
  gs::PoseGraph g;
  for (int i = 0; i < 60; ++i) g.addPose2(i, i == 0 ? truth[0] : gs::Pose2{Eigen::Vector2d(u(rng), u(rng)), u(rng)});
  g.addPoint2(1000, Eigen::Vector2d(u(rng), u(rng)));
  auto add = [&](int i, int j) { g.addBetween2(i, j, gs::compose(gs::inverse(truth[i]), truth[j]), Eigen::Matrix3d::Identity()); };
  for (int i = 0; i + 1 < 60; ++i) add(i, i + 1);
  for (int i = 20; i < 60; i += 7) add(i - 20, i);
  const Eigen::Vector2d landmark(3.0, 4.0);
  g.addPose2Point2(10, 1000, gs::rotation2(truth[10].theta).transpose() * (landmark - truth[10].t),
                   Eigen::Matrix2d::Identity());
  return g;
}

gs::PoseGraph garbage3d(std::vector<gs::Pose3>& truth) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  gs::Pose3 p;
  for (int i = 0; i < 50; ++i) {
    truth.push_back(p);
    gs::Pose3 s;
    s.t = Eigen::Vector3d(1.0, 0.1, 0.2);
    s.q = gs::expSO3(Eigen::Vector3d(0.1, -0.2, 0.4));
    p = gs::compose(p, s);
  }
  gs::PoseGraph g;
  for (int i = 0; i < 50; ++i) {
    gs::Pose3 v;
    v.t = Eigen::Vector3d(u(rng), u(rng), u(rng));
    v.q = gs::expSO3(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    g.addPose3(i, i == 0 ? truth[0] : v);
  }
  auto add = [&](int i, int j) { g.addBetween3(i, j, gs::compose(gs::inverse(truth[i]), truth[j]), gs::Matrix6d::Identity()); };
  for (int i = 0; i + 1 < 50; ++i) add(i, i + 1);
  for (int i = 15; i < 50; i += 4) add(i - 15, i);
  return g;
}

}  // namespace

TEST(Initialization, OdometryAndChordalRecoverNoiseFree2d) {
  for (auto method : {gs::Initialization::kOdometry, gs::Initialization::kChordal}) {
    std::vector<gs::Pose2> truth;
    gs::PoseGraph g = garbage2d(truth);
    ASSERT_GT(g.chi2(), 100.0);
    gs::initialize(g, method);
    EXPECT_LT(g.chi2(), 1e-18);
    for (int i = 0; i < 60; ++i) {
      EXPECT_LT((g.pose2(i).t - truth[i].t).norm(), 1e-9);
    }
    EXPECT_LT((g.variable(1000).point.head<2>() - Eigen::Vector2d(3.0, 4.0)).norm(), 1e-9);
  }
}

TEST(Initialization, OdometryAndChordalRecoverNoiseFree3d) {
  for (auto method : {gs::Initialization::kOdometry, gs::Initialization::kChordal}) {
    std::vector<gs::Pose3> truth;
    gs::PoseGraph g = garbage3d(truth);
    gs::initialize(g, method);
    EXPECT_LT(g.chi2(), 1e-18);
    for (int i = 0; i < 50; ++i) {
      EXPECT_LT((g.pose3(i).t - truth[i].t).norm(), 1e-9);
      EXPECT_LT(g.pose3(i).q.angularDistance(truth[i].q), 1e-9);
    }
  }
}

TEST(Initialization, ChordalThenSolversAgreeOnIntel) {
  gs::PoseGraph base = gs::readG2o(kData + "input_INTEL_g2o.g2o");
  const double raw = base.chi2();
  gs::initializeChordal(base);
  EXPECT_LT(base.chi2(), raw / 1000.0);  // chordal is far better than the stored odometry guess
  double reference = -1.0;
  for (auto alg : {gs::Algorithm::kDogleg, gs::Algorithm::kLevenbergMarquardt}) {
    gs::PoseGraph g = base;
    gs::OptimizerOptions o;
    o.algorithm = alg;
    o.max_iterations = 300;
    const auto sum = gs::Optimizer(o).optimize(g);
    EXPECT_TRUE(sum.converged) << sum.termination;
    if (reference < 0) reference = sum.final_chi2;
    EXPECT_NEAR(sum.final_chi2, reference, 1e-6 * reference);
  }
}

TEST(Initialization, ChordalOnMitReachesTheBasinOfTheGoodOptimum) {
  // From its stored guess MIT ends in a poor local minimum; from chordal it converges to chi2 ~ 41.
  gs::PoseGraph g = gs::readG2o(kData + "MIT.g2o");
  gs::initializeChordal(g);
  const auto sum = gs::Optimizer().optimize(g);
  EXPECT_TRUE(sum.converged);
  EXPECT_LT(sum.final_chi2, 42.0);
}
