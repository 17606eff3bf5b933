#include <gtest/gtest.h>

#include <cmath>

#include "cairn/sim/simulator.hpp"

using namespace cairn::sim;

namespace {
std::uint64_t runDigest(const World& world, std::uint64_t seed, double seconds, std::vector<PersonState>* people_out = nullptr) {
  SimConfig cfg;
  cfg.seed = seed;
  Simulator sim(world, cfg);
  sim.followRoute(world.routes.at("corridor_patrol"));
  SimOutput out;
  sim.advance(seconds, out);
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const auto& s : out.scans) h = scanDigest(s, h);
  for (const auto& o : out.odometry) {
    const double v[3] = {o.pose.x, o.pose.y, o.pose.theta};
    for (double x : v) h = (h ^ std::hash<double>{}(x)) * 0x100000001b3ULL;
  }
  if (people_out) *people_out = sim.people();
  return h;
}
}  // namespace

TEST(Simulator, SameSeedGivesByteIdenticalStreams) {
  const World office = loadWorld(resolveWorldPath("office"));
  std::vector<PersonState> pa, pb;
  const auto a = runDigest(office, 5, 15.0, &pa);
  const auto b = runDigest(office, 5, 15.0, &pb);
  const auto c = runDigest(office, 6, 15.0);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t i = 0; i < pa.size(); ++i) {
    EXPECT_EQ(pa[i].id, pb[i].id);
    EXPECT_EQ(pa[i].position.x, pb[i].position.x);
  }
}

TEST(Simulator, RatesStampsAndFrames) {
  const World office = loadWorld(resolveWorldPath("office"));
  SimConfig cfg;
  cfg.laser.rate = 15.0;
  cfg.odom_rate = 50.0;
  Simulator sim(office, cfg);
  SimOutput out;
  sim.advance(2.0, out);
  ASSERT_EQ(out.scans.size(), 30u);
  ASSERT_EQ(out.odometry.size(), 100u);
  ASSERT_EQ(out.ground_truth.size(), 100u);
  EXPECT_DOUBLE_EQ(out.scans[0].stamp, 0.0);
  EXPECT_NEAR(out.scans[29].stamp, 29 / 15.0, 0.006);  // on the 10 ms physics grid
  EXPECT_NEAR(out.odometry[99].stamp, 1.98, 1e-9);
  EXPECT_EQ(out.odometry[0].frame_id, "odom");
  EXPECT_EQ(out.odometry[0].child_frame_id, "base_link");
  EXPECT_EQ(out.ground_truth[0].frame_id, "map");
  EXPECT_EQ(out.scans[0].ranges.size(), 720u);
  EXPECT_NEAR(sim.time(), 2.0, 1e-12);
  // a second advance continues the streams without gaps or duplicates
  SimOutput more;
  sim.advance(1.0, more);
  ASSERT_EQ(more.scans.size(), 15u);
  EXPECT_GT(more.scans[0].stamp, out.scans.back().stamp);
}

TEST(Simulator, ScriptedRouteDrivesAlongTheCorridorWithOdometryDrift) {
  const World office = loadWorld(resolveWorldPath("office"));
  SimConfig cfg;
  cfg.crowd = false;
  cfg.odometry.scale_error = 0.01;
  Simulator sim(office, cfg);
  sim.followRoute({{20.0, office.robot_start.y}}, RouteConfig{.speed = 1.0});
  SimOutput out;
  sim.advance(40.0, out);
  EXPECT_FALSE(sim.routeActive());
  EXPECT_NEAR(sim.groundTruth().x, 20.0, 0.2);
  EXPECT_NEAR(sim.groundTruth().y, office.robot_start.y, 0.2);
  EXPECT_EQ(sim.robot().stallCount(), 0u);
  // odometry: ~1 % systematic error over 18 m plus a few cm random
  const double dist_true = sim.groundTruth().x - office.robot_start.x;
  const double dist_odom = sim.odometry().pose.x - office.robot_start.x;
  EXPECT_NEAR(dist_odom - dist_true, 0.01 * dist_true, 0.12);
  // the corridor is 2.1 m wide: side beams at ±90° see the corridor walls at ~1.05 m
  const LaserScan& s = out.scans.back();
  const int left = static_cast<int>(std::lround((M_PI / 2 - s.angle_min) / s.angle_increment));
  const float side = std::min(s.ranges[left], s.ranges[left - 1]);
  EXPECT_TRUE(std::isinf(side) || side > 0.9F);
}

TEST(Simulator, LaserSeesALegPairOfAScriptedWalker) {
  World w = parseWorld(
      "walls: [[[-10,-10],[10,-10],[10,10],[-10,10],[-10,-10]]]\n"
      "people: [{kind: scripted, waypoints: [[3,0],[4,0]], speed: 0.01}]\n"
      "robot: {start: [0, 0, 0]}\n",
      "t.yaml");
  SimConfig cfg;
  cfg.laser.noise_sigma = 0.0;
  cfg.laser.outlier_prob = 0.0;
  cfg.laser.resolution = 0.25 * M_PI / 180;
  Simulator sim(w, cfg);
  SimOutput out;
  sim.advance(0.05, out);
  ASSERT_FALSE(out.scans.empty());
  const LaserScan& s = out.scans.front();
  // count clusters of returns closer than 5 m (the walls are >= 9.8 m away)
  int clusters = 0;
  bool in = false;
  for (float r : s.ranges) {
    const bool near = r < 5.0F;
    if (near && !in) ++clusters;
    in = near;
  }
  EXPECT_EQ(clusters, 2);
  ASSERT_EQ(sim.people().size(), 1u);
  EXPECT_NEAR(sim.people()[0].position.x, 3.0 + 0.05 * 0.01, 1e-9);  // walked 0.05 s at 1 cm/s
}

TEST(Simulator, EveryRouteOfTheShippedWorldsIsDrivable) {
  // World sanity: the scripted routes pass doors and aisles without the robot touching walls, doors or
  // furniture (the robot stalls on contact), at t = 0 when the scheduled doors are open.
  for (const auto& name : shippedWorlds()) {
    const World world = loadWorld(resolveWorldPath(name));
    ASSERT_FALSE(world.routes.empty()) << name;
    for (const auto& [route_name, waypoints] : world.routes) {
      SimConfig cfg;
      cfg.crowd = false;
      cfg.laser.rate = 1.0;  // scans are not needed here
      Simulator sim(world, cfg);
      sim.followRoute(waypoints, RouteConfig{.speed = 1.0});
      SimOutput out;
      while (sim.routeActive() && sim.time() < 900.0) {
        sim.advance(0.5, out);
        out = {};
      }
      EXPECT_FALSE(sim.routeActive()) << name << "/" << route_name << " stuck at " << sim.groundTruth().x << ", "
                                      << sim.groundTruth().y;
      // Every physics step counts (stalled() is only the last step of each advance()).
      EXPECT_EQ(sim.robot().stallCount(), 0u) << name << "/" << route_name;
    }
  }
}

TEST(Simulator, RobotStallsAtAClosedDoor) {
  const World w = parseWorld(
      "walls: [[[-5,-5],[5,-5],[5,5],[-5,5],[-5,-5]], [[1,-5],[1,-0.6]], [[1,0.6],[1,5]]]\n"
      "doors: [{hinge: [1, -0.6], latch: [1, 0.6], schedule: [{t: 0, open: false}, {t: 10, open: true}]}]\n"
      "robot: {start: [-2, 0, 0]}\n",
      "t.yaml");
  SimConfig cfg;
  Simulator sim(w, cfg);
  sim.followRoute({{3, 0}}, RouteConfig{.speed = 0.5});
  SimOutput out;
  sim.advance(9.0, out);
  EXPECT_TRUE(sim.robot().stalled());
  EXPECT_NEAR(sim.groundTruth().x, 1.0 - cfg.robot.footprint_radius, 0.03);
  sim.advance(15.0, out);  // the door opens at t = 10 (swings away) and the robot drives through
  EXPECT_FALSE(sim.routeActive());
  EXPECT_NEAR(sim.groundTruth().x, 3.0, 0.2);
}
