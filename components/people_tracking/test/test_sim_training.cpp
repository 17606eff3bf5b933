// Training data from the simulator (tools/sim_training.hpp): labels from components/sim ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "cairn/people_tracking/bench.hpp"
#include "sim_training.hpp"

using namespace cairn::people_tracking;
namespace sim = cairn::sim;

namespace {

// A 10 m room around the origin with one legs-only table at (3, 0) and one walker walking away from the robot
// along -x (hip axis across the line of sight, so both legs are visible).
sim::World testWorld() {
  sim::World w;
  w.name = "test";
  const sim::Vec2 c[4] = {{-5, -5}, {5, -5}, {5, 5}, {-5, 5}};
  for (int i = 0; i < 4; ++i) w.walls.push_back({c[i], c[(i + 1) % 4]});
  sim::Furniture table;
  table.name = "table";
  table.length = 1.2;
  table.width = 0.8;
  table.legs_only = true;
  table.leg_radius = 0.03;
  table.poses = {sim::Pose2{3.0, 0.0, 0.0}};
  w.furniture.push_back(table);
  sim::PeopleSource walker;
  walker.kind = "scripted";
  walker.waypoints = {{-1.5, 0.0}, {-4.0, 0.0}};
  walker.speed = 0.6;
  w.people.push_back(walker);
  w.computeBounds();
  return w;
}

}  // namespace

TEST(SimTraining, LabelsMatchTheGroundTruthGeometry) {
  const sim::World world = testWorld();
  sim::SimConfig cfg;
  cfg.seed = 5;
  cfg.crowd = false;
  cfg.start = sim::Pose2{0.0, 0.0, 0.0};
  sim::Simulator s(world, cfg);
  sim::SimOutput out;
  s.advance(1.0, out);
  out = {};
  // Step until a scan falls due; the state before that step is what it saw.
  std::vector<sim::PersonState> people;
  sim::Pose2 pose;
  double t = 0;
  while (out.scans.empty()) {
    people = s.people();
    pose = s.groundTruth();
    t = s.time();
    s.advance(cfg.physics_dt, out);
  }
  ASSERT_EQ(people.size(), 1u);
  SimLabelStats st;
  const auto clusters =
      labelSimScan(out.scans.back(), sim::compose(pose, cfg.laser.mount), people, world, t, {}, {}, &st);
  std::size_t pos = 0, table_legs = 0, walls = 0;
  for (const SimLabelledCluster& c : clusters) {
    const Eigen::Vector2d body(people[0].position.x, people[0].position.y);
    if (c.sample.positive) {
      ++pos;
      // Independent of the labeller's own test: a leg is within hip half-width + leg radius (+ slack) of the body.
      EXPECT_LT((c.world_centroid - body).norm(), 0.35);
      EXPECT_EQ(c.person, people[0].id);
      EXPECT_EQ(c.sample.object_class, ObjectClass::kPersonLeg);
      continue;
    }
    EXPECT_GT((c.world_centroid - body).norm(), 0.5) << "negative cluster on the walker";
    // Table leg corners: (3 ± (0.6 - 0.03), ±(0.4 - 0.03)).
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        if ((c.world_centroid - Eigen::Vector2d(3.0 + sx * 0.57, sy * 0.37)).norm() < 0.1) {
          ++table_legs;
          EXPECT_EQ(c.sample.object_class, ObjectClass::kTableLeg);
        }
    if (std::abs(std::abs(c.world_centroid.x()) - 5.0) < 0.1 || std::abs(std::abs(c.world_centroid.y()) - 5.0) < 0.1) {
      ++walls;
      EXPECT_EQ(c.sample.object_class, ObjectClass::kWall);
    }
  }
  EXPECT_GE(pos, 1u);
  EXPECT_LE(pos, 2u);
  EXPECT_GE(table_legs, 2u);  // the far legs may hide behind the near ones
  EXPECT_GE(walls, 1u);
  EXPECT_EQ(st.positives, pos);
}

TEST(SimTraining, GeneratedDataIsDeterministicAndHasBothLabels) {
  SimTrainingParams p;
  p.worlds = {"apartment"};
  p.episodes = 3;
  p.scans_per_episode = 2;
  p.seed = 7;
  const auto a = simLabelledClusters(p), b = simLabelledClusters(p);
  ASSERT_EQ(a.size(), b.size());
  std::size_t pos = 0, furniture = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].sample.features, b[i].sample.features);
    EXPECT_EQ(a[i].sample.positive, b[i].sample.positive);
    pos += a[i].sample.positive;
    furniture += a[i].sample.object_class == ObjectClass::kTableLeg || a[i].sample.object_class == ObjectClass::kChairLeg;
    if (a[i].sample.positive) {
      EXPECT_GE(a[i].person, 0);
    }
  }
  EXPECT_GT(pos, 0u);
  EXPECT_GT(a.size() - pos, pos);
  EXPECT_GT(furniture, 0u);
}

// `cairn people bench --world <sim world>`: the world's geometry goes into the bench's scenes, the robot stands at
// the world's start pose, and the trajectories are centred on it. In the test world's 10 m room the walls cut the
// view that the auto world (walls 1.5 m outside the trajectories) leaves open; a wall across the room hides half.
TEST(BenchInSimWorld, WorldGeometryRobotStartAndTrajectoryOffset) {
  sim::World w = testWorld();
  w.walls.push_back({{0.5, -5}, {0.5, 5}});  // a wall 0.5 m in front of the robot, across the whole room
  w.robot_start = sim::Pose2{0.0, 0.0, 0.0};
  Scene scene;
  addWorldGeometry(w, 0.0, scene);
  EXPECT_EQ(scene.segments.size(), 5u);
  EXPECT_EQ(scene.circles.size(), 4u);  // the table's legs

  BenchParams p;
  p.trajectories = std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/eth_seq_eth_obsmat_head400.txt";
  p.seed = 3;
  const BenchResult open = runBench(p);
  p.world = "test";
  p.world_geometry = [&w](double t, Scene& s) { addWorldGeometry(w, t, s); };
  p.robot_start = Pose2{0.0, 0.0, 0.0};
  const BenchResult walled = runBench(p);
  EXPECT_EQ(walled.scans, open.scans);
  EXPECT_GT(open.mean_people_counted, 2.0);
  EXPECT_GT(walled.mean_people_counted, 0.1);                       // people behind the robot are seen
  EXPECT_LT(walled.mean_people_counted, 0.7 * open.mean_people_counted);  // the wall in front hides many
  // Moving the trajectories 50 m away leaves nobody in range.
  p.trajectory_offset = Pose2{50.0, 0.0, 0.0};
  EXPECT_EQ(runBench(p).cairn.mot.gt, 0u);
  // Without geometry a named world is an error.
  p.world_geometry = nullptr;
  EXPECT_THROW(runBench(p), InputError);
}

// The apartment's hallway ends in two wall ends 7 m in front of the robot, which the classifier takes for legs:
// phantom tracks for the whole run. With the world's geometry as static map they are gone.
TEST(BenchInSimWorld, StaticMapRemovesPhantomTracksOnWallEnds) {
  const auto world = std::make_shared<const sim::World>(sim::loadWorld(sim::resolveWorldPath("apartment")));
  BenchParams p;
  p.trajectories = std::string(CAIRN_SOURCE_ROOT) + "/test/data/people/eth_seq_eth_obsmat_head400.txt";
  p.seed = 3;
  p.world = "apartment";
  p.world_geometry = [world](double t, Scene& s) { addWorldGeometry(*world, t, s); };
  p.robot_start = Pose2{world->robot_start.x, world->robot_start.y, world->robot_start.theta};
  const BenchResult plain = runBench(p);
  p.static_map = true;
  const BenchResult mapped = runBench(p);
  EXPECT_GT(plain.cairn.mot.fp, plain.scans);  // at least one phantom per scan on average
  EXPECT_LT(mapped.cairn.mot.fp, plain.cairn.mot.fp / 10);
  EXPECT_GT(mapped.cairn.mot.mota(), plain.cairn.mot.mota());
}
