#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "cairn/people_tracking/features.hpp"

using namespace cairn::people_tracking;

namespace {
double F(const FeatureVector& f, Feature k) { return f[static_cast<std::size_t>(k)]; }

Cluster arc(const Eigen::Vector2d& center, double r, double a0, double a1, int n) {
  Cluster c;
  for (int i = 0; i < n; ++i) {
    const double a = a0 + (a1 - a0) * i / (n - 1);
    c.points.emplace_back(center + r * Eigen::Vector2d(std::cos(a), std::sin(a)));
  }
  return c;
}
}  // namespace

TEST(Features, RegistryNamesAreUniqueAndDescribed) {
  std::set<std::string_view> names;
  for (const auto& info : featureRegistry()) {
    EXPECT_FALSE(info.description.empty());
    names.insert(info.name);
  }
  EXPECT_EQ(names.size(), kNumFeatures);
  EXPECT_EQ(featureRegistry()[static_cast<std::size_t>(Feature::kWidth)].name, "width");
}

TEST(Features, CircleArcLikeALeg) {
  // Visible half of a 0.07 m leg at 3 m, facing the sensor.
  const Cluster c = arc({3.0, 0.0}, 0.07, M_PI / 2, 3 * M_PI / 2, 9);
  const auto f = computeFeatures(c);
  EXPECT_EQ(F(f, Feature::kNumPoints), 9.0);
  EXPECT_NEAR(F(f, Feature::kCircleRadius), 0.07, 1e-9);
  EXPECT_NEAR(F(f, Feature::kCircularity), 0.0, 1e-12);
  EXPECT_GT(F(f, Feature::kLinearity), 1e-4);
  EXPECT_NEAR(F(f, Feature::kMeanCurvature), 1.0 / 0.07, 1e-6);  // Menger curvature of a circle is 1/r
  EXPECT_NEAR(F(f, Feature::kMeanAngularDifference), M_PI / 8, 1e-9);  // turning angle = arc step
  EXPECT_NEAR(F(f, Feature::kWidth), 0.14, 1e-9);
  const double chord = 2 * 0.07 * std::sin(M_PI / 16);
  EXPECT_NEAR(F(f, Feature::kBoundaryLength), 8 * chord, 1e-9);
  EXPECT_NEAR(F(f, Feature::kBoundaryRegularity), 0.0, 1e-12);
  EXPECT_NEAR(F(f, Feature::kDistance), c.centroid().norm(), 1e-12);
  EXPECT_LT(F(f, Feature::kDistance), 3.0);
}

TEST(Features, StraightLineLikeAWall) {
  Cluster c;
  for (int i = 0; i < 11; ++i) c.points.emplace_back(2.0, -0.5 + 0.1 * i);
  c.jump_prev = 0.4;
  c.jump_next = 1.5;
  const auto f = computeFeatures(c);
  EXPECT_NEAR(F(f, Feature::kLinearity), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(F(f, Feature::kCircleRadius), 10.0);
  EXPECT_NEAR(F(f, Feature::kMeanCurvature), 0.0, 1e-9);
  EXPECT_NEAR(F(f, Feature::kMeanAngularDifference), 0.0, 1e-9);
  EXPECT_NEAR(F(f, Feature::kWidth), 1.0, 1e-12);
  EXPECT_NEAR(F(f, Feature::kBoundaryLength), 1.0, 1e-12);
  EXPECT_NEAR(F(f, Feature::kDistance), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(F(f, Feature::kJumpPrev), 0.4);
  EXPECT_DOUBLE_EQ(F(f, Feature::kJumpNext), 1.5);
  // Std from centroid of 11 evenly spaced points over 1 m: sqrt(sum((k*0.1)^2, k=-5..5) / 10) = sqrt(0.11).
  EXPECT_NEAR(F(f, Feature::kStdFromCentroid), std::sqrt(0.11), 1e-12);
  EXPECT_NEAR(F(f, Feature::kMeanAbsDevMedian), 2 * (0.1 + 0.2 + 0.3 + 0.4 + 0.5) / 11, 1e-12);
}

TEST(Features, IrregularSpacing) {
  Cluster c;
  c.points = {{1, 0}, {1, 0.1}, {1, 0.2}, {1, 0.5}};
  const auto f = computeFeatures(c);
  // Distances 0.1, 0.1, 0.3: mean 0.5/3, sample std with n-1 = 3 in our definition (population of gaps).
  const double m = 0.5 / 3;
  const double sd = std::sqrt(((0.1 - m) * (0.1 - m) * 2 + (0.3 - m) * (0.3 - m)) / 3);
  EXPECT_NEAR(F(f, Feature::kBoundaryRegularity), sd, 1e-12);
}

TEST(Features, DegenerateClustersDoNotProduceNaN) {
  Cluster one;
  one.points = {{1, 1}};
  Cluster same;
  same.points = {{1, 1}, {1, 1}, {1, 1}};
  for (const Cluster& c : {one, same, Cluster{}})
    for (double v : computeFeatures(c)) EXPECT_TRUE(std::isfinite(v));
}

TEST(Features, FeatureSetsAreVersioned) {
  const FeatureSet all = featureSet("arras14@1");
  EXPECT_EQ(all.features.size(), kNumFeatures);
  EXPECT_EQ(all.key(), "arras14@1");
  const FeatureSet s5 = featureSet("stuede5@1");
  ASSERT_EQ(s5.features.size(), 5u);
  FeatureVector v{};
  for (std::size_t i = 0; i < kNumFeatures; ++i) v[i] = static_cast<double>(i);
  const auto sel = s5.select(v);
  EXPECT_EQ(sel[0], static_cast<float>(Feature::kNumPoints));
  EXPECT_EQ(sel[1], static_cast<float>(Feature::kDistance));
  EXPECT_EQ(s5.featureNames()[1], "distance");
  EXPECT_THROW(featureSet("stuede5@2"), InputError);
  EXPECT_THROW(featureSet("nope"), InputError);
}
