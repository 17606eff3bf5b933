#include <gtest/gtest.h>

#include <Eigen/LU>

#include "cairn/people_tracking/fusion.hpp"
#include "cairn/people_tracking/scene.hpp"

using namespace cairn::people_tracking;

namespace {
PersonDetection det(double x, double y, double sigma, double conf = 0.8, int source = 0) {
  PersonDetection d;
  d.position = {x, y};
  d.covariance = sigma * sigma * Eigen::Matrix2d::Identity();
  d.confidence = conf;
  d.source = source;
  return d;
}
}  // namespace

TEST(Fusion, WeightedAverageByInformation) {
  const PersonDetection f = fusePair(det(0, 0, 0.1), det(0.2, 0, 0.1));
  EXPECT_TRUE(f.position.isApprox(Eigen::Vector2d(0.1, 0.0)));
  EXPECT_NEAR(f.covariance(0, 0), 0.005, 1e-12);
  EXPECT_NEAR(f.confidence, 0.96, 1e-12);
  const PersonDetection g = fusePair(det(0, 0, 0.05), det(0.2, 0, 0.2));  // 16x more information in the first
  EXPECT_NEAR(g.position.x(), 0.2 / 17.0, 1e-12);
}

TEST(Fusion, NearestPairsFusedOthersAppended) {
  const std::vector<PersonDetection> a{det(0, 0, 0.1), det(1.0, 0, 0.1), det(5, 5, 0.1)};
  const std::vector<PersonDetection> b{det(1.1, 0, 0.1, 0.8, 1), det(0.3, 0, 0.1, 0.8, 1), det(-5, 0, 0.1, 0.8, 1)};
  const auto f = fuseDetections({a, b});
  ASSERT_EQ(f.size(), 4u);  // (a1,b0) closest pair, then (a0,b1), then a2 and b2 appended
  EXPECT_TRUE(f[0].position.isApprox(Eigen::Vector2d(1.05, 0)));
  EXPECT_TRUE(f[1].position.isApprox(Eigen::Vector2d(0.15, 0)));
  EXPECT_TRUE(f[2].position.isApprox(Eigen::Vector2d(5, 5)));
  EXPECT_TRUE(f[3].position.isApprox(Eigen::Vector2d(-5, 0)));
  // Gate: nothing is fused beyond max_pair_distance.
  FusionParams tight;
  tight.max_pair_distance = 0.05;
  EXPECT_EQ(fuseDetections({a, b}, tight).size(), 6u);
  EXPECT_TRUE(fuseDetections({}).empty());
}

// gate_chi2: a camera-like detection, precise in bearing (y) and 0.4 m uncertain in range (x), pairs with the
// laser detection along its line of sight, not with the Euclidean-nearer one beside it.
TEST(Fusion, MahalanobisGatePairsAlongTheLongAxis) {
  const std::vector<PersonDetection> laser{det(5.0, 0.0, 0.05), det(5.5, 0.35, 0.05)};
  PersonDetection cam = det(5.6, 0.0, 1.0, 0.9, 1);
  cam.covariance = Eigen::Vector2d(0.4 * 0.4, 0.05 * 0.05).asDiagonal();
  const std::vector<PersonDetection> camera{cam};
  FusionParams euclid;
  euclid.max_pair_distance = 1.0;
  const auto e = nearestPairs(laser, camera, euclid);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].first, 1u);  // 0.36 m beside it beats 0.6 m along the line of sight
  FusionParams gated = euclid;
  gated.gate_chi2 = 9.21;
  const auto g = nearestPairs(laser, camera, gated);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].first, 0u);
  const PersonDetection f = fusePair(laser[0], camera[0]);
  EXPECT_NEAR(f.position.y(), 0.0, 1e-9);
  EXPECT_LT(f.position.x(), 5.05);  // the laser's 5 cm beat the camera's 40 cm along x
  gated.gate_chi2 = 1.0;            // too tight for 0.6 m at 0.4 m sigma: nothing fused
  EXPECT_TRUE(nearestPairs(laser, camera, gated).empty());
}

TEST(Fusion, TwoLaserSourcesOnOneScene) {
  // Two lasers look at the same three people from different poses; detections are transformed into the common
  // frame and fused: one fused detection per person, each more certain than either input.
  Scene scene;
  std::vector<WalkerState> people(3);
  people[0].position = {2.0, 0.5};
  people[1].position = {3.0, -1.5};
  people[2].position = {4.0, 1.5};
  for (std::size_t i = 0; i < people.size(); ++i) {
    people[i].heading = 0.5 * static_cast<double>(i);
    people[i].stride_amplitude = 0.15;
    people[i].gait_phase = 1.0;
    addWalker(scene, people[i], static_cast<int>(i));
  }
  const auto model = std::make_shared<const LegClassifier>(LegClassifier::load(
      std::string(CAIRN_SOURCE_ROOT) + "/components/people_tracking/models/leg_svm_arras14.yml"));
  const PersonDetector detector(model);
  const Pose2 poses[2] = {Pose2{0, 0, 0}, Pose2{6.0, 0.5, M_PI}};
  std::vector<std::vector<PersonDetection>> sources;
  std::mt19937_64 rng(4);
  for (int s = 0; s < 2; ++s) {
    auto dets = detector.detect(renderScan(scene, poses[s], LaserModel{}, 0.0, rng).scan);
    for (auto& d : dets) {
      d.position = poses[s].transform(d.position);
      d.covariance = poses[s].rotation() * d.covariance * poses[s].rotation().transpose();
      d.source = s;
    }
    ASSERT_EQ(dets.size(), 3u) << "source " << s;
    sources.push_back(dets);
  }
  const auto fused = fuseDetections(sources);
  ASSERT_EQ(fused.size(), 3u);
  for (const auto& w : people) {
    double best = 1e9;
    const PersonDetection* match = nullptr;
    for (const auto& f : fused)
      if ((f.position - w.position).norm() < best) best = (f.position - w.position).norm(), match = &f;
    EXPECT_LT(best, 0.12);
    for (const auto& s : sources)
      for (const auto& d : s)
        if ((d.position - match->position).norm() < 0.5) {
          EXPECT_LT(match->covariance.determinant(), d.covariance.determinant());
        }
  }
}
