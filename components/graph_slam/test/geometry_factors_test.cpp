// Analytic vs numeric Jacobians of every factor, manifold updates and the g2o error conventions.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "cairn/graph_slam/factors.hpp"
#include "cairn/graph_slam/geometry.hpp"
#include "cairn/graph_slam/pose_graph.hpp"
#include "cairn/graph_slam/robust_kernel.hpp"

namespace gs = cairn::graph_slam;

namespace {

gs::Pose2 randomPose2(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  return gs::Pose2{Eigen::Vector2d(u(rng), u(rng)), gs::normalizeAngle(u(rng))};
}

gs::Pose3 randomPose3(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  gs::Pose3 p;
  p.t = Eigen::Vector3d(u(rng), u(rng), u(rng));
  p.q = gs::expSO3(Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.7);
  return p;
}

// Central differences of f(delta) (error as a function of the manifold update) at delta = 0.
template <int R, int D, typename F>
Eigen::Matrix<double, R, D> numericJacobian(F f) {
  Eigen::Matrix<double, R, D> j;
  const double h = 1e-6;
  for (int k = 0; k < D; ++k) {
    Eigen::Matrix<double, D, 1> d = Eigen::Matrix<double, D, 1>::Zero();
    d[k] = h;
    const Eigen::Matrix<double, R, 1> ep = f(d);
    d[k] = -h;
    const Eigen::Matrix<double, R, 1> em = f(d);
    j.col(k) = (ep - em) / (2.0 * h);
  }
  return j;
}

}  // namespace

TEST(Geometry, NormalizeAngleRange) {
  EXPECT_NEAR(gs::normalizeAngle(3.0 * std::numbers::pi), std::numbers::pi, 1e-12);
  EXPECT_NEAR(gs::normalizeAngle(-3.0 * std::numbers::pi), std::numbers::pi, 1e-12);
  EXPECT_NEAR(gs::normalizeAngle(0.5 + 4.0 * std::numbers::pi), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(gs::normalizeAngle(-0.25), -0.25);
}

TEST(Geometry, ExpLogRoundTripAndComposeInverse) {
  std::mt19937 rng(7);
  for (int i = 0; i < 50; ++i) {
    const gs::Pose3 a = randomPose3(rng);
    const Eigen::Vector3d w = gs::logSO3(a.q);
    EXPECT_LT(w.norm(), std::numbers::pi + 1e-9);
    EXPECT_TRUE(gs::expSO3(w).isApprox(a.q, 1e-12) || gs::expSO3(w).coeffs().isApprox(-a.q.coeffs(), 1e-12));
    const gs::Pose3 id = gs::compose(a, gs::inverse(a));
    EXPECT_LT(id.t.norm(), 1e-12);
    EXPECT_NEAR(std::abs(id.q.w()), 1.0, 1e-12);
    const gs::Pose2 b = randomPose2(rng);
    const gs::Pose2 id2 = gs::compose(gs::inverse(b), b);
    EXPECT_LT(id2.t.norm(), 1e-12);
    EXPECT_NEAR(id2.theta, 0.0, 1e-12);
  }
}

TEST(Geometry, PoseAtInterpolatesAndContinuesTheLastMotionWithinTheTolerance) {
  // Odometry of a robot driving straight at 0.5 m/s with heading 0.3 rad, sampled every 0.1 s.
  const double heading = 0.3, speed = 0.5;
  auto at = [&](double t) { return gs::Pose2{speed * t * Eigen::Vector2d(std::cos(heading), std::sin(heading)), heading}; };
  std::deque<gs::StampedPose2> odom;
  for (int k = 0; k <= 5; ++k) odom.push_back({0.1 * k, at(0.1 * k)});
  auto expectAt = [&](double t, const gs::Pose2& want) {
    const auto p = gs::poseAt(odom, t, 0.2);
    ASSERT_TRUE(p.has_value()) << t;
    EXPECT_LT((p->t - want.t).norm(), 1e-9) << t;
    EXPECT_NEAR(gs::normalizeAngle(p->theta - want.theta), 0.0, 1e-9) << t;
  };
  expectAt(0.25, at(0.25));  // between samples
  // A scan 0.1 s newer than the last odometry (it came first): the motion continues; holding the last sample
  // would put the robot 5 cm back.
  expectAt(0.6, at(0.6));
  expectAt(0.7, at(0.7));
  EXPECT_FALSE(gs::poseAt(odom, 0.75, 0.2).has_value());  // beyond the tolerance
  expectAt(-0.1, at(0.0));                                 // before the first: the first
  EXPECT_FALSE(gs::poseAt(odom, -0.3, 0.2).has_value());
  // Samples 10 ms apart at the end: the motion continued is that over >= 50 ms, not the last sample's noise.
  std::deque<gs::StampedPose2> jitter = odom;
  jitter.push_back({0.51, gs::Pose2{at(0.51).t + Eigen::Vector2d(0.0, 0.003), heading}});
  const auto j = gs::poseAt(jitter, 0.6, 0.2);
  ASSERT_TRUE(j.has_value());
  EXPECT_LT((j->t - at(0.6).t).norm(), 0.01);
  // Turning in place at 1 rad/s: the heading continues across +-pi.
  std::deque<gs::StampedPose2> turn{{0.0, gs::Pose2{Eigen::Vector2d::Zero(), 2.9}}, {0.1, gs::Pose2{Eigen::Vector2d::Zero(), 3.0}}};
  const auto r = gs::poseAt(turn, 0.3, 0.2);
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(gs::normalizeAngle(r->theta - 3.2), 0.0, 1e-9);
  // One sample: held; none: nothing.
  EXPECT_LT((gs::poseAt(std::deque<gs::StampedPose2>{{1.0, at(1.0)}}, 1.1, 0.2)->t - at(1.0).t).norm(), 1e-12);
  EXPECT_FALSE(gs::poseAt({}, 0.0, 0.2).has_value());
}

TEST(Geometry, RetractIsRightPerturbationForSE3AndAdditiveForSE2) {
  std::mt19937 rng(3);
  const gs::Pose3 x = randomPose3(rng);
  gs::Vector6d d;
  d << 0.1, -0.2, 0.3, 0.05, -0.02, 0.04;
  const gs::Pose3 r = gs::retract(x, d);
  gs::Pose3 delta;
  delta.t = d.head<3>();
  delta.q = gs::expSO3(d.tail<3>());
  const gs::Pose3 expect = gs::compose(x, gs::Pose3{delta.t, Eigen::Quaterniond::Identity()});
  EXPECT_TRUE(r.t.isApprox(expect.t, 1e-12));
  EXPECT_TRUE(r.q.isApprox(x.q * delta.q, 1e-12));
  const gs::Pose2 p{Eigen::Vector2d(1, 2), 3.1};
  const gs::Pose2 q = gs::retract(p, Eigen::Vector3d(0.5, -0.5, 0.1));
  EXPECT_NEAR(q.t.x(), 1.5, 1e-15);
  EXPECT_NEAR(q.theta, 3.2 - 2.0 * std::numbers::pi, 1e-12);  // wrapped
}

TEST(Factors, Between2MatchesG2oConventionAndNumericJacobians) {
  std::mt19937 rng(11);
  for (int i = 0; i < 100; ++i) {
    const gs::Pose2 xi = randomPose2(rng), xj = randomPose2(rng), z = randomPose2(rng);
    Eigen::Matrix3d ji, jj;
    const Eigen::Vector3d e = gs::errorBetween2(xi, xj, z, &ji, &jj);
    // g2o: error = (Z^-1 * (Xi^-1 * Xj)).toVector()
    const gs::Pose2 ref = gs::compose(gs::inverse(z), gs::compose(gs::inverse(xi), xj));
    EXPECT_TRUE(e.head<2>().isApprox(ref.t, 1e-10));
    EXPECT_NEAR(e.z(), ref.theta, 1e-10);
    // Skip configurations where the angle error sits on the wrap-around.
    if (std::abs(e.z()) > 3.0) continue;
    const auto ni = numericJacobian<3, 3>([&](const Eigen::Vector3d& d) {
      return gs::errorBetween2(gs::retract(xi, d), xj, z, nullptr, nullptr);
    });
    const auto nj = numericJacobian<3, 3>([&](const Eigen::Vector3d& d) {
      return gs::errorBetween2(xi, gs::retract(xj, d), z, nullptr, nullptr);
    });
    EXPECT_LT((ji - ni).norm(), 1e-7) << ji << "\n" << ni;
    EXPECT_LT((jj - nj).norm(), 1e-7);
  }
}

TEST(Factors, Between3MatchesG2oConventionAndNumericJacobians) {
  std::mt19937 rng(12);
  for (int i = 0; i < 100; ++i) {
    const gs::Pose3 xi = randomPose3(rng), xj = randomPose3(rng), z = randomPose3(rng);
    gs::Matrix6d ji, jj;
    const gs::Vector6d e = gs::errorBetween3(xi, xj, z, &ji, &jj);
    const gs::Pose3 ref = gs::compose(gs::inverse(z), gs::compose(gs::inverse(xi), xj));
    EXPECT_TRUE(e.head<3>().isApprox(ref.t, 1e-10));
    Eigen::Quaterniond q = ref.q.normalized();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    EXPECT_TRUE(e.tail<3>().isApprox(q.vec(), 1e-10));
    if (q.w() < 1e-3) continue;  // sign flip of w >= 0 is not differentiable there
    const auto ni = numericJacobian<6, 6>([&](const gs::Vector6d& d) {
      return gs::errorBetween3(gs::retract(xi, d), xj, z, nullptr, nullptr);
    });
    const auto nj = numericJacobian<6, 6>([&](const gs::Vector6d& d) {
      return gs::errorBetween3(xi, gs::retract(xj, d), z, nullptr, nullptr);
    });
    EXPECT_LT((ji - ni).norm(), 1e-7) << ji << "\n" << ni;
    EXPECT_LT((jj - nj).norm(), 1e-7) << jj << "\n" << nj;
  }
}

TEST(Factors, PriorsAndPosePointNumericJacobians) {
  std::mt19937 rng(13);
  for (int i = 0; i < 50; ++i) {
    const gs::Pose2 x2 = randomPose2(rng), z2 = randomPose2(rng);
    Eigen::Matrix3d jp2;
    const Eigen::Vector3d e2 = gs::errorPrior2(x2, z2, &jp2);
    if (std::abs(e2.z()) < 3.0) {
      const auto n2 = numericJacobian<3, 3>(
          [&](const Eigen::Vector3d& d) { return gs::errorPrior2(gs::retract(x2, d), z2, nullptr); });
      EXPECT_LT((jp2 - n2).norm(), 1e-7);
    }
    const gs::Pose3 x3 = randomPose3(rng), z3 = randomPose3(rng);
    gs::Matrix6d jp3;
    gs::errorPrior3(x3, z3, &jp3);
    const auto n3 = numericJacobian<6, 6>(
        [&](const gs::Vector6d& d) { return gs::errorPrior3(gs::retract(x3, d), z3, nullptr); });
    EXPECT_LT((jp3 - n3).norm(), 1e-7);

    const Eigen::Vector2d p2(1.5, -0.7), zp2(0.3, 0.2);
    Eigen::Matrix<double, 2, 3> jx;
    Eigen::Matrix2d jp;
    gs::errorPose2Point2(x2, p2, zp2, &jx, &jp);
    const auto nx = numericJacobian<2, 3>([&](const Eigen::Vector3d& d) {
      return gs::errorPose2Point2(gs::retract(x2, d), p2, zp2, nullptr, nullptr);
    });
    const auto np = numericJacobian<2, 2>(
        [&](const Eigen::Vector2d& d) { return gs::errorPose2Point2(x2, p2 + d, zp2, nullptr, nullptr); });
    EXPECT_LT((jx - nx).norm(), 1e-7);
    EXPECT_LT((jp - np).norm(), 1e-7);

    const Eigen::Vector3d p3(0.5, 1.0, -2.0), zp3(0.1, 0.2, 0.3);
    Eigen::Matrix<double, 3, 6> jx3;
    Eigen::Matrix3d jpp3;
    gs::errorPose3Point3(x3, p3, zp3, &jx3, &jpp3);
    const auto nx3 = numericJacobian<3, 6>([&](const gs::Vector6d& d) {
      return gs::errorPose3Point3(gs::retract(x3, d), p3, zp3, nullptr, nullptr);
    });
    const auto np3 = numericJacobian<3, 3>(
        [&](const Eigen::Vector3d& d) { return gs::errorPose3Point3(x3, p3 + d, zp3, nullptr, nullptr); });
    EXPECT_LT((jx3 - nx3).norm(), 1e-7);
    EXPECT_LT((jpp3 - np3).norm(), 1e-7);
  }
}

TEST(RobustKernel, DerivativesMatchNumericAndDownweightLargeErrors) {
  for (const char* spec : {"huber:1.5", "cauchy:1", "gm:2", "dcs:1"}) {
    const gs::RobustKernel k = gs::RobustKernel::parse(spec);
    for (double s : {0.1, 0.9, 2.0, 10.0, 1000.0}) {
      double r = 0, d = 0, rp = 0, rm = 0, tmp = 0;
      k.evaluate(s, r, d);
      const double h = 1e-6 * std::max(1.0, s);
      k.evaluate(s + h, rp, tmp);
      k.evaluate(s - h, rm, tmp);
      EXPECT_NEAR(d, (rp - rm) / (2 * h), 1e-5) << spec << " s=" << s;
      EXPECT_LE(r, s + 1e-12) << spec;  // every kernel is below the quadratic
    }
    double r = 0, d = 0;
    k.evaluate(1e6, r, d);
    EXPECT_LT(d, 0.01) << spec;  // a gross outlier gets a small weight
  }
  EXPECT_THROW(gs::RobustKernel::parse("tukey:1"), std::invalid_argument);
  EXPECT_THROW(gs::RobustKernel::parse("huber:-1"), std::invalid_argument);
  EXPECT_THROW(gs::RobustKernel::parse("huber:abc"), std::invalid_argument);
}

TEST(PoseGraph, RejectsBadStructure) {
  gs::PoseGraph g;
  g.addPose2(0, {});
  g.addPose3(1, {});
  EXPECT_THROW(g.addPose2(0, {}), std::invalid_argument);
  EXPECT_THROW(g.addBetween2(0, 1, {}, Eigen::Matrix3d::Identity()), std::invalid_argument);  // kind
  EXPECT_THROW(g.addBetween2(0, 7, {}, Eigen::Matrix3d::Identity()), std::invalid_argument);  // missing
  EXPECT_THROW(g.addBetween2(0, 0, {}, Eigen::Matrix3d::Identity()), std::invalid_argument);  // self loop
  const auto v0 = g.structureVersion();
  g.setPose2(0, gs::Pose2{Eigen::Vector2d(1, 1), 0.2});
  EXPECT_EQ(g.structureVersion(), v0);  // values do not change the structure
  g.setFixed(0);
  EXPECT_NE(g.structureVersion(), v0);
}
