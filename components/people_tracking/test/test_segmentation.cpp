#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "cairn/people_tracking/scene.hpp"
#include "cairn/people_tracking/segmentation.hpp"

using namespace cairn::people_tracking;

namespace {
LaserScan makeScan(std::size_t n, double inc, float fill) {
  LaserScan s;
  s.angle_min = -0.5 * inc * static_cast<double>(n - 1);
  s.angle_increment = inc;
  s.range_min = 0.05;
  s.range_max = 20.0;
  s.ranges.assign(n, fill);
  return s;
}
}  // namespace

TEST(Segmentation, SplitsAtRangeJumps) {
  LaserScan s = makeScan(60, 0.01, 5.0f);
  for (std::size_t i = 20; i < 30; ++i) s.ranges[i] = 2.0f;  // an object in front of the wall
  const auto clusters = segmentScan(s);
  ASSERT_EQ(clusters.size(), 3u);
  EXPECT_EQ(clusters[1].beams.front(), 20u);
  EXPECT_EQ(clusters[1].beams.back(), 29u);
  EXPECT_NEAR(clusters[1].jump_prev, 3.0, 0.01);
  EXPECT_NEAR(clusters[1].jump_next, 3.0, 0.01);
  EXPECT_DOUBLE_EQ(clusters[0].jump_prev, SegmentationParams{}.jump_cap);
}

TEST(Segmentation, ThresholdAdaptsToRange) {
  // A far wall: neighbouring returns are 8 m * 0.01 rad = 0.08 m apart.
  LaserScan s = makeScan(40, 0.01, 8.0f);
  SegmentationParams fixed;
  fixed.jump_base = 0.05;
  fixed.jump_beam_factor = 0.0;
  EXPECT_EQ(segmentScan(s, fixed).size(), 0u);  // every point alone, below min_points
  // Same fixed part; only the range term (3 beam spacings = 0.24 m at 8 m) can join the points.
  SegmentationParams adaptive = fixed;
  adaptive.jump_beam_factor = 3.0;
  EXPECT_EQ(segmentScan(s, adaptive).size(), 1u);
  // At 1 m the same angular spacing is 0.01 m apart: joined by the fixed part alone.
  EXPECT_EQ(segmentScan(makeScan(40, 0.01, 1.0f), fixed).size(), 1u);
}

TEST(Segmentation, InvalidBeamsSplitUnlessSingleDropout) {
  LaserScan s = makeScan(40, 0.01, 3.0f);
  s.ranges[10] = std::numeric_limits<float>::quiet_NaN();  // single dropout: tolerated
  EXPECT_EQ(segmentScan(s).size(), 1u);
  s.ranges[11] = std::numeric_limits<float>::infinity();   // two in a row: split
  EXPECT_EQ(segmentScan(s).size(), 2u);
  s.ranges[30] = 50.0f;  // beyond range_max counts as no return
  s.ranges[31] = 0.01f;  // below range_min
  EXPECT_EQ(segmentScan(s).size(), 3u);
}

TEST(Segmentation, DropsSmallClusters) {
  LaserScan s = makeScan(40, 0.01, std::numeric_limits<float>::infinity());
  s.ranges[5] = s.ranges[6] = 2.0f;
  s.ranges[20] = s.ranges[21] = s.ranges[22] = 2.0f;
  const auto clusters = segmentScan(s);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].points.size(), 3u);
}

TEST(Segmentation, RejectsBadMetadata) {
  LaserScan s = makeScan(10, 0.01, 1.0f);
  LaserScan bad = s;
  bad.ranges.clear();
  EXPECT_THROW(segmentScan(bad), InputError);
  bad = s;
  bad.angle_increment = 0.0;
  EXPECT_THROW(segmentScan(bad), InputError);
  bad = s;
  bad.angle_increment = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(segmentScan(bad), InputError);
  bad = s;
  bad.angle_increment = 1.0;  // 10 beams * 1 rad > 2 pi: metadata does not match the number of ranges
  EXPECT_THROW(segmentScan(bad), InputError);
  bad = s;
  bad.range_max = 0.0;
  EXPECT_THROW(segmentScan(bad), InputError);
  EXPECT_NO_THROW(segmentScan(s));
}

// Two legs, one partly behind the other (0.12 m deeper, 0.16 m to the side) at 5 m: closer in depth than the jump
// threshold (0.19 m there), so one cluster, split by gapSplitIndex at the step from one leg to the other; one leg,
// one leg with a missing return and a wall are not split.
TEST(Segmentation, GapSplitFindsTheStepBetweenTwoLegsInOneCluster) {
  LaserModel laser;
  laser.noise_sigma = 0.0;
  laser.dropout_prob = 0.0;
  std::mt19937_64 rng(1);
  Scene two;
  two.addCircle({5.0, 0.0}, 0.06, ObjectClass::kPersonLeg, 0);
  two.addCircle({5.12, 0.16}, 0.06, ObjectClass::kPersonLeg, 0);
  const SimScan sim = renderScan(two, Pose2{}, laser, 0.0, rng);
  const auto clusters = segmentScan(sim.scan);
  ASSERT_EQ(clusters.size(), 1u);
  const Cluster& c = clusters[0];
  const std::size_t i = gapSplitIndex(c, sim.scan.angle_increment, 2.5, 2.5);
  ASSERT_GT(i, 0u);
  ASSERT_LT(i, c.points.size());
  // Every return before the split is on one leg, every one after it on the other.
  for (std::size_t k = 0; k < c.points.size(); ++k)
    EXPECT_EQ(sim.hit_object[c.beams[k]], sim.hit_object[c.beams[k < i ? 0 : c.points.size() - 1]]) << k;
  EXPECT_NE(sim.hit_object[c.beams[0]], sim.hit_object[c.beams.back()]);
  // The step must stand out from the other distances by gap_ratio.
  EXPECT_EQ(gapSplitIndex(c, sim.scan.angle_increment, 100.0, 2.5), 0u);

  Scene one;
  one.addCircle({5.0, 0.0}, 0.08, ObjectClass::kPersonLeg, 0);
  SimScan leg = renderScan(one, Pose2{}, laser, 0.0, rng);
  const auto single = segmentScan(leg.scan);
  ASSERT_EQ(single.size(), 1u);
  EXPECT_EQ(gapSplitIndex(single[0], leg.scan.angle_increment, 2.5, 2.5), 0u);
  // One missing return inside the leg (tolerated by the segmentation): a step of two beam spacings.
  leg.scan.ranges[single[0].beams[single[0].beams.size() / 2]] = std::numeric_limits<float>::quiet_NaN();
  const auto dropped = segmentScan(leg.scan);
  ASSERT_EQ(dropped.size(), 1u);
  EXPECT_EQ(gapSplitIndex(dropped[0], leg.scan.angle_increment, 2.5, 2.5), 0u);

  LaserScan wall = makeScan(40, 0.01, 3.0f);
  const auto flat = segmentScan(wall);
  ASSERT_EQ(flat.size(), 1u);
  EXPECT_EQ(gapSplitIndex(flat[0], wall.angle_increment, 2.5, 2.5), 0u);
  Cluster two_points;
  two_points.points = {{5.0, 0.0}, {5.2, 0.3}};
  EXPECT_EQ(gapSplitIndex(two_points, 0.01, 2.5, 2.5), 0u);
}

