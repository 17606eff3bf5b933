#include <gtest/gtest.h>

#include <cmath>

#include "cairn/people_tracking/masking.hpp"

using namespace cairn::people_tracking;

namespace {
LaserScan fullScan() {
  LaserScan s;
  s.angle_min = -M_PI;
  s.angle_increment = 2 * M_PI / 720;
  s.range_min = 0.05;
  s.range_max = 20;
  s.ranges.assign(720, 5.0f);
  return s;
}
}  // namespace

TEST(Masking, RadiusFromLegSeparation) {
  MaskParams p;
  EXPECT_DOUBLE_EQ(personRadius(0.3, p), 0.15 + 0.08 + 0.10);
  EXPECT_DOUBLE_EQ(personRadius(0.0, p), p.default_radius);
  EXPECT_DOUBLE_EQ(personRadius(0.01, p), p.min_radius);
}

TEST(Masking, MasksExactlyTheBeamsBetweenTheTangents) {
  LaserScan s = fullScan();
  const MaskCircle c{{2.0, 0.0}, 0.5};
  const double half = std::asin(0.25);
  const std::size_t n = maskScan(s, {c});
  std::size_t expected = 0;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    const double a = s.angle(i);
    const bool inside = std::abs(a) <= half;
    expected += inside;
    EXPECT_EQ(std::isnan(s.ranges[i]), inside) << i << " angle " << a;
  }
  EXPECT_EQ(n, expected);
  EXPECT_GT(n, 50u);  // 2 * 0.2527 rad / 0.00873 rad ~ 58 beams
  EXPECT_EQ(maskScan(s, {c}), 0u);  // already masked beams are not counted again
}

TEST(Masking, WrapsAroundBehindTheSensorAndHandlesInsideCase) {
  LaserScan s = fullScan();
  const std::size_t n = maskScan(s, {{{-3.0, 0.0}, 0.3}});  // bearing pi: both ends of the scan
  EXPECT_GT(n, 10u);
  EXPECT_TRUE(std::isnan(s.ranges.front()));
  EXPECT_TRUE(std::isnan(s.ranges.back()));
  EXPECT_FALSE(std::isnan(s.ranges[360]));
  LaserScan t = fullScan();
  EXPECT_EQ(maskScan(t, {{{0.1, 0.0}, 0.3}}), 361u);  // sensor inside: the front half plane, |angle| <= pi/2
  LaserScan bad;
  EXPECT_THROW(maskScan(bad, {}), InputError);
}
