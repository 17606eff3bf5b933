#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cairn/sim/diff_drive.hpp"
#include "cairn/sim/route.hpp"

using namespace cairn::sim;
constexpr double kPi = std::numbers::pi;

TEST(Kinematics, ArcIntegrationIsExact) {
  // quarter circle of radius 2: v = 1, w = 0.5, t = pi
  const Pose2 p = integrateArc({0, 0, 0}, {1.0, 0.5}, kPi);
  EXPECT_NEAR(p.x, 2.0, 1e-12);
  EXPECT_NEAR(p.y, 2.0, 1e-12);
  EXPECT_NEAR(p.theta, kPi / 2, 1e-12);
  // many small steps give the same pose as one big one
  Pose2 q{1, -1, 0.3};
  for (int i = 0; i < 1000; ++i) q = integrateArc(q, {0.7, -0.4}, 0.003);
  const Pose2 r = integrateArc({1, -1, 0.3}, {0.7, -0.4}, 3.0);
  EXPECT_NEAR(q.x, r.x, 1e-9);
  EXPECT_NEAR(q.y, r.y, 1e-9);
}

TEST(Kinematics, VelocityAndAccelerationLimits) {
  DiffDriveConfig c;
  c.max_v = 1.0;
  c.max_acc = 0.5;
  c.max_dec = 1.0;
  DiffDrive robot(c, {});
  robot.setCommand({5.0, 9.0}, 0.0);
  EXPECT_DOUBLE_EQ(robot.command().v, 1.0);     // clamped to max_v
  EXPECT_DOUBLE_EQ(robot.command().w, c.max_w);
  double t = 0;
  for (int i = 0; i < 100; ++i, t += 0.01) {
    robot.setCommand({5.0, 0.0}, t);
    robot.step(0.01, t);
  }
  EXPECT_NEAR(robot.velocity().v, 0.5, 1e-9);  // 1 s at 0.5 m/s²
  for (int i = 0; i < 200; ++i, t += 0.01) {
    robot.setCommand({5.0, 0.0}, t);
    robot.step(0.01, t);
  }
  EXPECT_NEAR(robot.velocity().v, 1.0, 1e-9);
  // 200 steps accelerating (semi-implicit Euler: velocity first, then pose: sum 0.005 k * 0.01) + 1 s at 1 m/s
  EXPECT_NEAR(robot.pose().x, 1.005 + 1.0, 1e-9);
  for (int i = 0; i < 50; ++i, t += 0.01) {
    robot.setCommand({0.0, 0.0}, t);
    robot.step(0.01, t);
  }
  EXPECT_NEAR(robot.velocity().v, 0.5, 1e-9);  // braking at 1 m/s²
  // command timeout: one forward command, then silence for > cmd_timeout -> brakes to zero
  robot.setCommand({1.0, 0.0}, t);
  for (int i = 0; i < 200; ++i, t += 0.01) robot.step(0.01, t);
  EXPECT_DOUBLE_EQ(robot.velocity().v, 0.0);
  const auto [wl, wr] = DiffDrive(c, {}).wheelSpeeds();
  EXPECT_DOUBLE_EQ(wl, 0.0);
  EXPECT_DOUBLE_EQ(wr, 0.0);
}

TEST(Kinematics, StallsAtWalls) {
  const SegmentGrid walls({{{2, -5}, {2, 5}, 0.3F}});
  DiffDriveConfig c;
  DiffDrive robot(c, {0, 0, 0});
  double t = 0;
  for (int i = 0; i < 1000; ++i, t += 0.01) {
    robot.setCommand({1.0, 0.0}, t);
    robot.step(0.01, t, &walls);
  }
  EXPECT_LE(robot.pose().x, 2.0 - c.footprint_radius + 1e-9);
  EXPECT_GT(robot.pose().x, 2.0 - c.footprint_radius - 0.02);
  EXPECT_TRUE(robot.stalled());
  const std::size_t stalls = robot.stallCount();
  EXPECT_GT(stalls, 100u);  // pushing against the wall for most of the 10 s
  // backing off is allowed
  for (int i = 0; i < 100; ++i, t += 0.01) {
    robot.setCommand({-0.3, 0.0}, t);
    robot.step(0.01, t, &walls);
  }
  EXPECT_FALSE(robot.stalled());
  EXPECT_EQ(robot.stallCount(), stalls);
  EXPECT_LT(robot.pose().x, 1.6);
}

TEST(Odometry, SystematicScaleErrorWithoutNoise) {
  OdometryNoiseConfig c;
  c.scale_error = 0.01;
  c.sigma_trans = c.sigma_rot = c.sigma_rot_per_m = 0.0;
  OdometryModel odom(c, {0, 0, 0}, Rng(1));
  for (int i = 1; i <= 1000; ++i) odom.update({0.01 * i, 0, 0});
  EXPECT_NEAR(odom.pose().x, 10.1, 1e-9);  // 1 % of 10 m
  EXPECT_NEAR(odom.pose().y, 0.0, 1e-12);
  c.scale_error = 0.0;
  c.heading_drift = 0.01;  // rad/m
  OdometryModel drift(c, {0, 0, 0}, Rng(1));
  for (int i = 1; i <= 1000; ++i) drift.update({0.01 * i, 0, 0});
  EXPECT_NEAR(drift.pose().theta, 0.1, 1e-9);
}

TEST(Odometry, RandomErrorGrowsWithSqrtDistanceIndependentOfStep) {
  // Variance of the distance error after D metres is sigma_trans² D whatever the step size.
  OdometryNoiseConfig c;
  c.scale_error = 0.0;
  c.sigma_trans = 0.02;
  c.sigma_rot = c.sigma_rot_per_m = 0.0;
  for (const double step : {0.01, 0.1}) {
    double sum = 0, sum2 = 0;
    const int runs = 400;
    for (int r = 0; r < runs; ++r) {
      OdometryModel odom(c, {0, 0, 0}, Rng(1000 + r));
      const int n = static_cast<int>(std::lround(4.0 / step));
      for (int i = 1; i <= n; ++i) odom.update({step * i, 0, 0});
      const double e = odom.pose().x - 4.0;
      sum += e;
      sum2 += e * e;
    }
    const double mean = sum / runs, sd = std::sqrt(sum2 / runs - mean * mean);
    EXPECT_NEAR(mean, 0.0, 0.01) << step;            // standard error 0.002
    EXPECT_NEAR(sd, 0.02 * std::sqrt(4.0), 0.006) << step;  // 0.04 ± 15 %
  }
}

TEST(Odometry, TracksTruthOnACircleWithoutNoise) {
  OdometryNoiseConfig c;
  c.scale_error = c.sigma_trans = c.sigma_rot = c.sigma_rot_per_m = 0.0;
  Pose2 truth{1, 2, 0.5};
  OdometryModel odom(c, truth, Rng(1));
  for (int i = 0; i < 2000; ++i) {
    truth = integrateArc(truth, {0.5, 0.3}, 0.01);
    odom.update(truth);
  }
  EXPECT_NEAR(odom.pose().x, truth.x, 1e-9);
  EXPECT_NEAR(odom.pose().y, truth.y, 1e-9);
  EXPECT_NEAR(odom.pose().theta, truth.theta, 1e-9);
}

TEST(Route, ReachesAllWaypointsInOrder) {
  RouteFollower route({{2, 0}, {2, 2}, {0, 2}});
  DiffDrive robot(DiffDriveConfig{}, {0, 0, 0});
  double t = 0;
  double closest_to_corner = 1e9;
  for (int i = 0; i < 6000 && !route.done(); ++i, t += 0.01) {
    robot.setCommand(route.command(robot.pose(), t), t);
    robot.step(0.01, t);
    closest_to_corner = std::min(closest_to_corner, std::hypot(robot.pose().x - 2, robot.pose().y - 2));
  }
  ASSERT_TRUE(route.done());
  EXPECT_LT(closest_to_corner, 0.16);
  EXPECT_NEAR(robot.pose().x, 0.0, 0.2);
  EXPECT_NEAR(robot.pose().y, 2.0, 0.2);
}

TEST(Odometry, RotationNoiseOfATurnInPlace) {
  // Turning by pi in place: heading error ~ N(pi * rotation_scale_error, sigma_rot² pi), no translation.
  OdometryNoiseConfig c;
  c.sigma_rot = 0.01;
  c.rotation_scale_error = 0.02;
  double sum = 0, sum2 = 0;
  const int runs = 500;
  for (int r = 0; r < runs; ++r) {
    OdometryModel odom(c, {0, 0, 0}, Rng(5000 + r));
    Pose2 truth{0, 0, 0};
    for (int i = 0; i < 300; ++i) {
      truth = integrateArc(truth, {0.0, kPi / 3.0}, 0.01);
      odom.update(truth);
    }
    const double e = normalizeAngle(odom.pose().theta - truth.theta);
    EXPECT_NEAR(odom.pose().x, 0.0, 1e-12);
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / runs, sd = std::sqrt(sum2 / runs - mean * mean);
  EXPECT_NEAR(mean, 0.02 * kPi, 0.003);
  EXPECT_NEAR(sd, 0.01 * std::sqrt(kPi), 0.003);
}

TEST(Route, DwellsAtEveryWaypoint) {
  // Stüde §4.3.1: simulated observation routes with stationary intermediate stops.
  RouteConfig cfg;
  cfg.dwell = 3.0;
  RouteFollower route({{1, 0}, {2, 0}}, cfg);
  DiffDrive robot(DiffDriveConfig{}, {0, 0, 0});
  double t = 0, stopped_near_first = 0;
  for (int i = 0; i < 3000 && !route.done(); ++i, t += 0.01) {
    robot.setCommand(route.command(robot.pose(), t), t);
    robot.step(0.01, t);
    if (std::abs(robot.pose().x - 1.0) < 0.2 && robot.velocity().v == 0.0) stopped_near_first += 0.01;
  }
  ASSERT_TRUE(route.done());
  // 3 s of dwell minus the ~0.1 s of braking from the approach speed (the dwell starts on arrival)
  EXPECT_GT(stopped_near_first, 2.7);
  EXPECT_LE(stopped_near_first, 3.0 + 1e-9);
  EXPECT_NEAR(robot.pose().x, 2.0, 0.2);
}
