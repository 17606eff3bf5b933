#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cairn/sim/diff_drive.hpp"
#include "cairn/sim/laser.hpp"
#include "cairn/sim/raycast.hpp"
#include "cairn/sim/world.hpp"

using namespace cairn::sim;
constexpr double kPi = std::numbers::pi;

namespace {
std::vector<Segment> square(double half) {
  const Vec2 c[4] = {{-half, -half}, {half, -half}, {half, half}, {-half, half}};
  std::vector<Segment> s;
  for (int i = 0; i < 4; ++i) s.push_back({c[i], c[(i + 1) % 4], 0.3F});
  return s;
}
Vec2 dir(double a) { return {std::cos(a), std::sin(a)}; }
}  // namespace

TEST(RayPrimitives, AnalyticSegmentAndCircle) {
  EXPECT_NEAR(raySegment({0, 0}, {1, 0}, {3, -1}, {3, 1}), 3.0, 1e-12);
  EXPECT_LT(raySegment({0, 0}, {-1, 0}, {3, -1}, {3, 1}), 0.0);  // behind
  EXPECT_LT(raySegment({0, 0}, {1, 0}, {3, 0.5}, {3, 1}), 0.0);  // misses the end
  EXPECT_NEAR(rayCircle({0, 0}, {1, 0}, {5, 0}, 0.5), 4.5, 1e-12);
  // offset by y = 0.3: chord entry at 5 - sqrt(0.25 - 0.09) = 4.6
  EXPECT_NEAR(rayCircle({0, 0.3}, {1, 0}, {5, 0}, 0.5), 4.6, 1e-12);
  EXPECT_LT(rayCircle({0, 0.6}, {1, 0}, {5, 0}, 0.5), 0.0);
  EXPECT_LT(rayCircle({5, 0}, {1, 0}, {5, 0}, 0.5), 0.0);  // inside
}

TEST(SegmentGrid, SquareRoomAnalytic) {
  const SegmentGrid grid(square(5.0), 0.5);
  for (int k = 0; k < 360; ++k) {
    const double a = k * kPi / 180.0;
    const RayHit h = grid.cast({0, 0}, dir(a), 30.0);
    ASSERT_TRUE(h.hit);
    // distance to the wall of a square: half / max(|cos|, |sin|)
    EXPECT_NEAR(h.range, 5.0 / std::max(std::abs(std::cos(a)), std::abs(std::sin(a))), 1e-9) << k;
  }
  EXPECT_FALSE(grid.cast({0, 0}, {1, 0}, 4.0).hit);  // beyond max range
  // ray starting outside the grid that enters it
  const RayHit h = grid.cast({-20, 0.1}, {1, 0}, 30.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.range, 15.0, 1e-9);
}

TEST(SegmentGrid, ALongThinWorldGetsCoarseCellsNotBillions) {
  // one wall 1e12 m long: the cell size came from the (zero) area and the grid needed ~4e9 cells (std::bad_alloc)
  const SegmentGrid grid({{{0, 0}, {1e12, 0}, 0.3F}, {{0, 1}, {10, 1}, 0.3F}});
  EXPECT_GE(grid.cellSize(), 1e9);
  const RayHit h = grid.cast({5, 0.5}, {0, 1}, 10.0);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.range, 0.5, 1e-9);
}

TEST(SegmentGrid, AgreesWithNaiveOnRandomScenes) {
  Rng rng(7);
  for (int scene = 0; scene < 5; ++scene) {
    std::vector<Segment> segs;
    for (int i = 0; i < 300; ++i) {
      const Vec2 a{rng.uniform(-20, 20), rng.uniform(-10, 10)};
      const double len = rng.uniform(0.05, 6.0), ang = rng.uniform(-kPi, kPi);
      segs.push_back({a, a + len * dir(ang), static_cast<float>(rng.uniform())});
    }
    const SegmentGrid grid(segs, scene == 0 ? 0.0 : 0.3 * (scene + 1));
    for (int r = 0; r < 2000; ++r) {
      const Vec2 o{rng.uniform(-22, 22), rng.uniform(-12, 12)};
      const Vec2 d = dir(rng.uniform(-kPi, kPi));
      const RayHit g = grid.cast(o, d, 25.0), n = castNaive(segs, o, d, 25.0);
      ASSERT_EQ(g.hit, n.hit) << scene << " " << r;
      if (g.hit) {
        ASSERT_NEAR(g.range, n.range, 1e-9);
        ASSERT_EQ(g.reflectivity, n.reflectivity);
      }
    }
  }
}

TEST(SegmentGrid, DistanceAndCollision) {
  const SegmentGrid grid(square(2.0), 0.5);
  EXPECT_NEAR(grid.distanceToNearest({1.5, 0}, 10.0), 0.5, 1e-12);
  EXPECT_TRUE(grid.intersectsDisc({1.7, 0}, 0.35));
  EXPECT_FALSE(grid.intersectsDisc({0, 0}, 0.35));
}

TEST(Laser, BeamLayoutFollowsLaserScanConvention) {
  LaserConfig c;
  c.fov = 2 * kPi;
  c.resolution = 0.5 * kPi / 180;
  EXPECT_EQ(c.beams(), 720);
  c.fov = kPi;
  EXPECT_EQ(c.beams(), 361);
  c.resolution = 0.25 * kPi / 180;
  EXPECT_EQ(c.beams(), 721);
  c.resolution = 0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
}

TEST(Laser, IdealScanInSquareRoomWithMountOffset) {
  const SegmentGrid grid(square(5.0));
  LaserConfig c;
  c.fov = kPi;
  c.resolution = kPi / 180;
  c.noise_sigma = 0;
  c.outlier_prob = 0;
  c.mount = {0.5, 0.0, 0.0};
  const LaserSimulator laser(c, grid);
  Rng rng(1);
  const LaserScan s = laser.scan({0, 0, kPi / 2}, 3.0, {}, {}, rng);  // robot faces +y, laser at (0, 0.5)
  ASSERT_EQ(s.ranges.size(), 181u);
  EXPECT_FLOAT_EQ(s.angle_min, static_cast<float>(-kPi / 2));
  EXPECT_NEAR(s.angle_max, kPi / 2, 1e-6);
  EXPECT_NEAR(s.ranges[90], 4.5, 1e-5);   // straight ahead (+y)
  EXPECT_NEAR(s.ranges[0], 5.0, 1e-5);    // -90° in laser frame = +x... robot faces +y, so right = +x
  EXPECT_NEAR(s.ranges[180], 5.0, 1e-5);
  EXPECT_DOUBLE_EQ(s.stamp, 3.0);
  EXPECT_FLOAT_EQ(s.intensities[90], 300.0F);
}

TEST(Laser, DynamicGeometryLegsDoorsMarkers) {
  const SegmentGrid grid(square(10.0));
  LaserConfig c;
  c.noise_sigma = 0;
  c.outlier_prob = 0;
  c.mount = {};
  const LaserSimulator laser(c, grid);
  Rng rng(1);
  const int n = c.beams();
  auto beamAt = [&](double a) { return static_cast<int>(std::lround((a - c.angleMin()) / c.resolution)) % n; };
  // two legs straight ahead at 3 m, 0.2 m apart; a door panel behind the robot; a marker to the left
  std::vector<Circle> circles = {{{3.0, 0.1}, 0.06, 0.3F}, {{3.0, -0.1}, 0.06, 0.3F}, {{0, 4}, 0.05, 1.0F}};
  std::vector<Segment> segs = {{{-2, -1}, {-2, 1}, 0.3F}};
  const LaserScan s = laser.scan({0, 0, 0}, 0, segs, circles, rng);
  const double leg_bearing = std::atan2(0.1, 3.0);
  EXPECT_NEAR(s.ranges[beamAt(leg_bearing)], std::hypot(3.0, 0.1) - 0.06, 2e-3);
  EXPECT_NEAR(s.ranges[beamAt(-leg_bearing)], std::hypot(3.0, 0.1) - 0.06, 2e-3);
  EXPECT_NEAR(s.ranges[beamAt(0.0)], 10.0, 1e-5);  // between the legs: the wall
  EXPECT_NEAR(s.ranges[beamAt(kPi)], 2.0, 1e-5);   // door (beam index wraps to 0 at -pi)
  EXPECT_NEAR(s.ranges[beamAt(kPi / 2)], 3.95, 1e-5);
  EXPECT_FLOAT_EQ(s.intensities[beamAt(kPi / 2)], 1000.0F);
  c.binary_intensity = true;
  const LaserSimulator binary(c, grid);
  const LaserScan b = binary.scan({0, 0, 0}, 0, segs, circles, rng);
  EXPECT_EQ(b.intensities[beamAt(kPi / 2)], 1.0F);
  EXPECT_EQ(b.intensities[beamAt(0.0)], 0.0F);
  // no return within range -> +inf (REP 117)
  LaserConfig shortc = c;
  shortc.range_max = 5.0;
  const LaserSimulator short_laser(shortc, grid);
  const LaserScan sh = short_laser.scan({0, 0, 0}, 0, {}, {}, rng);
  EXPECT_TRUE(std::isinf(sh.ranges[beamAt(0.0)]));
}

TEST(Laser, TableSeenOnlyByItsLegs) {
  // Yuan §4.2.3: of a table only the four legs are in the laser plane.
  const World w = parseWorld(
      "walls: [[[-10,-10],[10,-10],[10,10],[-10,10],[-10,-10]]]\n"
      "furniture: [{name: t, size: [1.6, 0.8], legs_only: true, leg_radius: 0.03, pose: [3, 0, 0]}]\n",
      "t.yaml");
  const SegmentGrid grid(w.walls);
  LaserConfig c;
  c.noise_sigma = 0;
  c.outlier_prob = 0;
  c.mount = {};
  c.resolution = 0.25 * kPi / 180;
  const LaserSimulator laser(c, grid);
  std::vector<Segment> segs;
  std::vector<Circle> circles;
  w.dynamicGeometry(0, segs, circles);
  Rng rng(3);
  const LaserScan s = laser.scan({0, 0, 0}, 0, segs, circles, rng);
  auto beamAt = [&](double a) { return static_cast<int>(std::lround((a - c.angleMin()) / c.resolution)); };
  EXPECT_NEAR(s.ranges[beamAt(0.0)], 10.0, 1e-5);  // under the table top
  const double leg_bearing = std::atan2(0.37, 2.23);  // front-left leg at (3 - 0.77, 0.37)
  EXPECT_NEAR(s.ranges[beamAt(leg_bearing)], std::hypot(2.23, 0.37) - 0.03, 5e-3);
}

TEST(Laser, NoiseStatisticsAndOutliers) {
  const SegmentGrid grid(square(5.0));
  LaserConfig c;
  c.noise_sigma = 0.05;
  c.outlier_prob = 0.0;
  c.mount = {};
  const LaserSimulator laser(c, grid);
  Rng rng(42);
  std::vector<RayHit> ideal;
  laser.castIdeal({0, 0, 0}, {}, {}, ideal);
  double sum = 0, sum2 = 0;
  int count = 0;
  for (int k = 0; k < 50; ++k) {
    const LaserScan s = laser.scan({0, 0, 0}, 0, {}, {}, rng);
    for (std::size_t i = 0; i < s.ranges.size(); ++i) {
      const double e = s.ranges[i] - ideal[i].range;
      sum += e;
      sum2 += e * e;
      ++count;
    }
  }
  const double mean = sum / count, sd = std::sqrt(sum2 / count - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.002);   // 36000 samples: standard error 0.00026
  EXPECT_NEAR(sd, 0.05, 0.0015);

  c.noise_sigma = 0.0;
  c.outlier_prob = 0.1;
  const LaserSimulator outl(c, grid);
  int shorter = 0, total = 0;
  for (int k = 0; k < 20; ++k) {
    const LaserScan s = outl.scan({0, 0, 0}, 0, {}, {}, rng);
    for (std::size_t i = 0; i < s.ranges.size(); ++i, ++total)
      if (s.ranges[i] < ideal[i].range - 1e-4) ++shorter;
  }
  EXPECT_NEAR(static_cast<double>(shorter) / total, 0.1, 0.015);
}

TEST(Laser, SameSeedSameScanDifferentSeedDifferentScan) {
  const SegmentGrid grid(square(5.0));
  const LaserSimulator laser(LaserConfig{}, grid);
  Rng a(5), b(5), c(6);
  const LaserScan sa = laser.scan({0.3, 0.2, 0.1}, 0, {}, {}, a);
  const LaserScan sb = laser.scan({0.3, 0.2, 0.1}, 0, {}, {}, b);
  const LaserScan sc = laser.scan({0.3, 0.2, 0.1}, 0, {}, {}, c);
  EXPECT_EQ(sa.ranges, sb.ranges);
  EXPECT_NE(sa.ranges, sc.ranges);
}

TEST(SegmentGrid, AgreesWithNaiveOnTheRealAtcMap) {
#if !CAIRN_SIM_HAVE_PNG
  GTEST_SKIP() << "built without libpng";
#endif
  const World w = parseWorld("map: " + std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/atc_map.yaml\n", "atc.yaml");
  const SegmentGrid grid(w.walls);
  Rng rng(3);
  int hits = 0;
  for (int r = 0; r < 300; ++r) {
    const Vec2 o{rng.uniform(w.bounds_min.x, w.bounds_max.x), rng.uniform(w.bounds_min.y, w.bounds_max.y)};
    const Vec2 d = dir(rng.uniform(-kPi, kPi));
    const RayHit g = grid.cast(o, d, 30.0), n = castNaive(w.walls, o, d, 30.0);
    ASSERT_EQ(g.hit, n.hit) << r;
    if (g.hit) {
      ASSERT_NEAR(g.range, n.range, 1e-9) << r;
    }
    hits += g.hit;
  }
  EXPECT_GT(hits, 100);  // the comparison is not vacuous (178 of 300 rays hit with this seed)
}

TEST(Laser, MotionDistortionCastsEachBeamFromItsOwnPose) {
  const SegmentGrid grid(square(10.0));
  LaserConfig c;
  c.noise_sigma = 0;
  c.outlier_prob = 0;
  c.mount = {};
  c.rate = 10.0;
  c.motion_distortion = true;
  const LaserSimulator laser(c, grid);
  Rng rng(1);
  const double dt = c.resolution / (2 * kPi) / c.rate;  // 1/7200 s between beams
  // driving forward at 1 m/s towards the wall at x = 10: the beam straight ahead (index 360) fires
  // 360 dt = 0.05 s after the first one, when the robot is 5 cm closer
  LaserScan s;
  laser.scan({0, 0, 0}, 0.0, {}, {}, rng, s, {1.0, 0.0});
  EXPECT_NEAR(s.ranges[360], 10.0 - 360 * dt * 1.0, 1e-5);
  EXPECT_NEAR(s.ranges[0], 10.0, 1e-5);  // first beam (backwards, -pi) from the start pose
  // a circle (leg) is still found by the culled dynamic path: same result as the naive per-beam check
  std::vector<Circle> legs = {{{3.0, 0.5}, 0.06, 0.3F}};
  laser.scan({0, 0, 0}, 0.0, {}, legs, rng, s, {0.8, 1.0});
  int found = 0;
  for (int i = 0; i < c.beams(); ++i) {
    const Pose2 p = integrateArc({0, 0, 0}, {0.8, 1.0}, i * dt);
    const double a = p.theta + c.angleMin() + i * c.resolution;
    const double t = rayCircle({p.x, p.y}, {std::cos(a), std::sin(a)}, legs[0].center, legs[0].radius);
    if (t >= 0) {
      ++found;
      EXPECT_NEAR(s.ranges[i], t, 1e-5) << i;
    }
  }
  EXPECT_GT(found, 0);
  // without velocity the distorted laser equals the plain one
  LaserScan still;
  laser.scan({1, 2, 0.3}, 0.0, {}, legs, rng, still);
  c.motion_distortion = false;
  const LaserSimulator plain(c, grid);
  LaserScan ref;
  plain.scan({1, 2, 0.3}, 0.0, {}, legs, rng, ref);
  EXPECT_EQ(still.ranges, ref.ranges);
}
