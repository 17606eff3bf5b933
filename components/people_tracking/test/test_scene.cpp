#include <gtest/gtest.h>

#include <map>

#include "cairn/people_tracking/features.hpp"
#include "cairn/people_tracking/scene.hpp"

using namespace cairn::people_tracking;

TEST(Scene, RendersLegAndWallWithLabels) {
  Scene scene;
  scene.addCircle({2.0, 0.0}, 0.07, ObjectClass::kPersonLeg, 7);
  scene.addSegment({5.0, -3.0}, {5.0, 3.0}, ObjectClass::kWall);
  LaserModel laser;
  laser.noise_sigma = 0.0;
  laser.dropout_prob = 0.0;
  std::mt19937_64 rng(1);
  const SimScan sim = renderScan(scene, Pose2{}, laser, 1.5, rng);
  EXPECT_DOUBLE_EQ(sim.scan.stamp, 1.5);
  // Beam straight ahead hits the front of the leg.
  const auto ahead = static_cast<std::size_t>(std::lround(-laser.angle_min / laser.angle_increment));
  EXPECT_NEAR(sim.scan.ranges[ahead], 1.93, 1e-5);
  const auto clusters = segmentScan(sim.scan);
  ASSERT_EQ(clusters.size(), 3u);  // wall left of the leg, the leg, wall right of the leg
  const ClusterLabel leg = labelCluster(clusters[1], sim, scene);
  EXPECT_TRUE(leg.is_person);
  EXPECT_EQ(leg.person, 7);
  EXPECT_NEAR(computeFeatures(clusters[1])[static_cast<std::size_t>(Feature::kCircleRadius)], 0.07, 1e-3);
  EXPECT_EQ(labelCluster(clusters[0], sim, scene).object_class, ObjectClass::kWall);
  EXPECT_FALSE(labelCluster(clusters[2], sim, scene).is_person);
}

TEST(Scene, SensorPoseMovesTheView) {
  Scene scene;
  scene.addCircle({0.0, 3.0}, 0.1, ObjectClass::kPole);
  LaserModel laser;
  laser.noise_sigma = 0.0;
  laser.dropout_prob = 0.0;
  std::mt19937_64 rng(1);
  const SimScan sim = renderScan(scene, Pose2{0.0, 1.0, M_PI / 2}, laser, 0.0, rng);
  const auto ahead = static_cast<std::size_t>(std::lround(-laser.angle_min / laser.angle_increment));
  EXPECT_NEAR(sim.scan.ranges[ahead], 1.9, 1e-5);
}

TEST(Scene, RandomScenesAreDeterministicAndMixed) {
  std::mt19937_64 a(42), b(42);
  const Scene sa = randomTrainingScene(a), sb = randomTrainingScene(b);
  ASSERT_EQ(sa.circles.size(), sb.circles.size());
  for (std::size_t i = 0; i < sa.circles.size(); ++i) EXPECT_EQ(sa.circles[i].center, sb.circles[i].center);
  int persons = 0, others = 0;
  std::mt19937_64 rng(3);
  for (int k = 0; k < 20; ++k) {
    const Scene s = randomTrainingScene(rng);
    for (ObjectClass c : s.object_class) (c == ObjectClass::kPersonLeg ? persons : others)++;
  }
  EXPECT_GT(persons, 20);
  EXPECT_GT(others, 100);
}

// TrainingSceneParams::group_probability 1: every generated person has a companion 0.45-0.8 m beside them (ids 2k
// and 2k+1); a person's centre is the mean of their two legs.
TEST(Scene, GroupScenesPairPeopleSideBySide) {
  TrainingSceneParams params;
  params.group_probability = 1.0;
  std::mt19937_64 rng(5);
  int pairs = 0;
  for (int k = 0; k < 20; ++k) {
    const Scene s = randomTrainingScene(rng, params);
    std::map<int, Eigen::Vector2d> centre;
    std::map<int, int> legs;
    for (const SceneCircle& c : s.circles) {
      const int p = s.object_person[static_cast<std::size_t>(c.object)];
      if (p < 0) continue;
      centre[p] = (legs[p]++ ? centre[p] : Eigen::Vector2d::Zero()) + 0.5 * c.center;
    }
    ASSERT_EQ(centre.size() % 2, 0u);
    for (const auto& [p, n] : legs) EXPECT_EQ(n, 2) << "person " << p;
    for (int p = 0; p + 1 < static_cast<int>(centre.size()); p += 2) {
      const double d = (centre[p] - centre[p + 1]).norm();
      EXPECT_GE(d, 0.45 - 1e-9);
      EXPECT_LE(d, 0.8 + 1e-9);
      ++pairs;
    }
  }
  EXPECT_GT(pairs, 20);
}

TEST(Scene, GaitSwingsLegsWhileWalking) {
  WalkerState w;
  w.heading = 0.0;
  for (int i = 0; i < 20; ++i) advanceGait(w, 0.12, 0.1);  // 1.2 m/s
  EXPECT_GT(w.stride_amplitude, 0.25);
  const auto legs = legCenters(w);
  EXPECT_NEAR((legs[0] + legs[1]).x() / 2, w.position.x(), 1e-12);
  EXPECT_NEAR((legs[0] - legs[1]).y(), 2 * w.hip_half_width, 1e-12);
}
