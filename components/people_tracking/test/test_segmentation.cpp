#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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
