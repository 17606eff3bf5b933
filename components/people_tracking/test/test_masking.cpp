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
  // "inside" mode with the sensor inside: every return inside the circle, behind the sensor too (the return at
  // 0.15 m straight back, 0.25 m from the centre, was kept), and nothing else.
  LaserScan u = fullScan();
  u.ranges[0] = 0.15f;    // angle -pi: (-0.15, 0), inside
  u.ranges[360] = 0.3f;   // angle 0: (0.3, 0), inside
  u.ranges[180] = 0.25f;  // angle -pi/2: (0, -0.25), 0.27 m from the centre: inside
  EXPECT_EQ(maskScan(u, {{{0.1, 0.0}, 0.3}}, MaskMode::kReturnsInside), 3u);
  EXPECT_TRUE(std::isnan(u.ranges[0]) && std::isnan(u.ranges[360]) && std::isnan(u.ranges[180]));
  LaserScan bad;
  EXPECT_THROW(maskScan(bad, {}), InputError);
}

TEST(Masking, InsideModeKeepsBeamsThatPassTheCircle) {
  // A person (circle r 0.4 at 2 m) in front of a wall at 5 m: beams between the tangents that end on the person
  // (range 1.7-2.3 m) are masked in both modes; beams that pass beside the legs and end on the wall, and beams
  // that end on something in front of the person (1 m), are kept by kReturnsInside only.
  LaserScan s = fullScan();
  const MaskCircle c{{2.0, 0.0}, 0.4};
  std::size_t on_person = 0, between = 0;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    const double a = s.angle(i);
    if (std::abs(a) > std::asin(0.2)) continue;
    ++between;
    if (i % 3 == 0) s.ranges[i] = 1.0f;                   // an obstacle in front of the person
    else if (i % 3 == 1) s.ranges[i] = static_cast<float>(2.0 * std::cos(a)), ++on_person;  // a leg (inside)
  }                                                        // i % 3 == 2: the wall at 5 m, between the legs
  LaserScan t = s;
  EXPECT_EQ(maskScan(s, {c}, MaskMode::kTangents), between);
  EXPECT_EQ(maskScan(t, {c}, MaskMode::kReturnsInside), on_person);
  for (std::size_t i = 0; i < t.ranges.size(); ++i)
    EXPECT_EQ(std::isnan(t.ranges[i]), std::abs(t.angle(i)) <= std::asin(0.2) && i % 3 == 1) << i;
  EXPECT_EQ(parseMaskMode("inside", "k"), MaskMode::kReturnsInside);
  EXPECT_EQ(parseMaskMode("tangents", "k"), MaskMode::kTangents);
  EXPECT_THROW(parseMaskMode("all", "mask.mode"), InputError);
}
