#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <algorithm>

#include "cairn/copa_map/gridifier.hpp"

using namespace cairn::copa_map;

namespace {

GridConfig smallGrid() {
  GridConfig c;
  c.cell_size = 1.0;
  c.time_bin = 100.0;
  c.origin_x = 0.0;
  c.origin_y = 0.0;
  c.nx = 10;
  c.ny = 10;
  c.fov_radius = 2.0;
  c.max_pose_gap = 1.0;
  c.min_duration = 0.0;
  c.rate_unit = 1.0;  // rates per second, easy to hand-compute
  return c;
}

// 20 m x 20 m map at 0.1 m, a wall along x = 5.0 .. 5.1 for y in [0, 10).
std::shared_ptr<OccupancyMap> wallMap() {
  auto m = std::make_shared<OccupancyMap>();
  m->width = 200;
  m->height = 200;
  m->resolution = 0.1;
  m->occupied.assign(200 * 200, 0);
  for (int cy = 0; cy < 100; ++cy) m->occupied[cy * 200 + 50] = 1;
  return m;
}

std::map<std::pair<int, int>, GridCell> byCell(const std::vector<GridCell>& cells, std::int64_t bin) {
  std::map<std::pair<int, int>, GridCell> out;
  for (const auto& c : cells)
    if (c.bin == bin) out[{c.ix, c.iy}] = c;
  return out;
}

}  // namespace

TEST(CopaGridifier, LineOfSightBlockedByWall) {
  auto m = wallMap();
  EXPECT_TRUE(m->lineOfSight(4.0, 2.0, 4.9, 7.0));
  EXPECT_FALSE(m->lineOfSight(4.0, 2.0, 6.0, 2.0));
  EXPECT_FALSE(m->lineOfSight(6.0, 3.0, 4.5, 3.5));
  EXPECT_TRUE(m->lineOfSight(4.0, 12.0, 6.0, 12.0));  // above the wall's end
}

// Hand-computed FOV case: robot parked at (4.2, 4.5) with r_fov = 2 m. Cell centres (ix+0.5, iy+0.5) within
// 2 m: ix in 2..5 for iy = 4 (dx = -1.7, -0.7, 0.3, 1.3), but ix = 5 (centre x = 5.5) is behind the wall.
TEST(CopaGridifier, FovCircleIsPrunedByRayCasting) {
  Gridifier g(smallGrid(), wallMap());
  const auto vis = g.visibleCells(4.2, 4.5);
  std::set<int> s(vis.begin(), vis.end());
  EXPECT_TRUE(s.count(4 * 10 + 2));
  EXPECT_TRUE(s.count(4 * 10 + 3));
  EXPECT_TRUE(s.count(4 * 10 + 4));
  EXPECT_FALSE(s.count(4 * 10 + 5));  // behind the wall
  EXPECT_FALSE(s.count(4 * 10 + 6));  // behind the wall and out of range
  EXPECT_FALSE(s.count(4 * 10 + 1));  // 3.7 m away
  // Without a map the cell behind the wall is visible.
  Gridifier free_g(smallGrid(), nullptr);
  const auto vis2 = free_g.visibleCells(4.2, 4.5);
  EXPECT_EQ(std::count(vis2.begin(), vis2.end(), 4 * 10 + 5), 1);
  // Count cells: every cell centre within the circle (brute force) minus those behind the wall.
  int expected = 0;
  for (int iy = 0; iy < 10; ++iy)
    for (int ix = 0; ix < 10; ++ix) {
      const double dx = ix + 0.5 - 4.2, dy = iy + 0.5 - 4.5;
      if (dx * dx + dy * dy <= 4.0 && ix + 0.5 < 5.0) ++expected;
    }
  EXPECT_EQ(static_cast<int>(vis.size()), expected);
}

TEST(CopaGridifier, DurationsCountsAndRatesAcrossBins) {
  Gridifier g(smallGrid(), wallMap());
  // Parked at (4.2, 4.5) from t = 50 s to t = 130 s (poses every 0.5 s), then moves to (2.5, 8.5) until 150 s.
  double t = 50.0;
  for (; t < 130.0; t += 0.5) g.addPose(t, 4.2, 4.5);
  for (; t <= 150.0; t += 0.5) g.addPose(t, 2.5, 8.5);
  // Three detections in cell (3,4) during bin 0, one in bin 1; one behind the wall (unobserved).
  g.addDetection(60.0, 3.4, 4.6);
  g.addDetection(70.0, 3.6, 4.4);
  g.addDetection(99.0, 3.1, 4.9);
  g.addDetection(110.0, 3.5, 4.5);
  g.addDetection(80.0, 5.5, 4.5);
  // Bin 0 ends at 100 s: flush at 120 s emits it and keeps bin 1 open.
  auto out0 = g.flush(120.0);
  auto b0 = byCell(out0, 0);
  ASSERT_TRUE(b0.count(std::make_pair(3, 4)));
  EXPECT_NEAR(b0[std::make_pair(3, 4)].duration, 50.0, 1e-9);  // observed 50..100 s
  EXPECT_DOUBLE_EQ(b0[std::make_pair(3, 4)].count, 3.0);
  EXPECT_NEAR(b0[std::make_pair(3, 4)].rate, 3.0 / 50.0, 1e-12);  // eq. 4.6
  EXPECT_DOUBLE_EQ(b0[std::make_pair(4, 4)].count, 0.0);
  EXPECT_DOUBLE_EQ(b0[std::make_pair(4, 4)].rate, smallGrid().rate_min);
  EXPECT_FALSE(b0.count(std::make_pair(5, 4)));  // never visible
  EXPECT_EQ(g.stats().detections_unobserved, 1u);
  EXPECT_DOUBLE_EQ(b0[std::make_pair(3, 4)].x1, 3.5);
  EXPECT_DOUBLE_EQ(b0[std::make_pair(3, 4)].x2, 4.5);
  EXPECT_GT(g.openEntries(), 0u);
  auto out1 = g.finish();
  auto b1 = byCell(out1, 1);
  ASSERT_TRUE(b1.count(std::make_pair(3, 4)));
  EXPECT_NEAR(b1[std::make_pair(3, 4)].duration, 30.0, 1e-9);  // 100..130 s
  EXPECT_NEAR(b1[std::make_pair(3, 4)].rate, 1.0 / 30.0, 1e-12);
  // (2, 8) is 4.3 m from the first stop and 0.5 m from the second one: observed 130..150 s only.
  ASSERT_TRUE(b1.count(std::make_pair(2, 8)));
  EXPECT_NEAR(b1[std::make_pair(2, 8)].duration, 20.0, 1e-9);
  EXPECT_EQ(g.openEntries(), 0u);
  // Late detections for emitted bins are rejected, not silently counted.
  g.addDetection(10.0, 3.5, 4.5);
  EXPECT_EQ(g.stats().detections_late, 1u);
}

TEST(CopaGridifier, PoseGapsAreNotObserved) {
  auto cfg = smallGrid();
  cfg.max_pose_gap = 2.0;
  Gridifier g(cfg, nullptr);
  g.addPose(0.0, 5.0, 5.0);
  g.addPose(50.0, 5.0, 5.0);  // 50 s gap: only 2 s credited
  g.addPose(51.0, 5.0, 5.0);
  auto out = g.finish();
  auto b0 = byCell(out, 0);
  ASSERT_TRUE(b0.count(std::make_pair(5, 5)));
  EXPECT_NEAR(b0[std::make_pair(5, 5)].duration, 3.0, 1e-12);
}

TEST(CopaGridifier, MinimumDurationDropsBrieflySeenCells) {
  auto cfg = smallGrid();
  cfg.min_duration = 20.0;
  Gridifier g(cfg, nullptr);
  for (double t = 0; t <= 10.0; t += 0.5) g.addPose(t, 5.0, 5.0);
  g.addDetection(5.0, 5.2, 5.2);
  auto out = g.finish();
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(g.stats().detections_unobserved, 1u);
}

// Counts and durations come from the same field of view (Stüde §4.2.2): a person standing in a cell the whole bin,
// tracked from beyond fov_radius, counts only while the cell is seen. Before, all 100 detections counted against
// 30 s of observation: a rate 3.3x too high.
TEST(CopaGridifier, DetectionsCountOnlyWhileTheirCellIsInView) {
  Gridifier g(smallGrid(), nullptr);
  int streamed = 0;
  for (int k = 0; k < 100; ++k) {  // streaming, as the component: each second the pose, then the detection
    const double t = k;
    g.addPose(t, k < 30 ? 3.5 : 8.5, 4.5);  // next to cell (3, 4) for 30 s, then 5 m away
    g.addDetection(t, 3.5, 4.5);
    ++streamed;
  }
  auto b0 = byCell(g.finish(), 0);
  ASSERT_TRUE(b0.count(std::make_pair(3, 4)));
  EXPECT_NEAR(b0[std::make_pair(3, 4)].duration, 30.0, 1e-9);
  EXPECT_DOUBLE_EQ(b0[std::make_pair(3, 4)].count, 30.0);  // t = 0 .. 29
  EXPECT_NEAR(b0[std::make_pair(3, 4)].rate, 1.0, 1e-12);   // one per second while seen
  EXPECT_EQ(g.stats().detections_unobserved, static_cast<std::uint64_t>(streamed - 30));
  // The same when the detections come after all poses (a batch): the credited intervals decide.
  Gridifier batch(smallGrid(), nullptr);
  for (int k = 0; k < 100; ++k) batch.addPose(k, k < 30 ? 3.5 : 8.5, 4.5);
  for (int k = 0; k < 100; ++k) batch.addDetection(k, 3.5, 4.5);
  auto c0 = byCell(batch.finish(), 0);
  EXPECT_DOUBLE_EQ(c0[std::make_pair(3, 4)].count, 30.0);  // t = 0 .. 29: seen in [0, 30)
}

TEST(CopaGridifier, StreamingMemoryIsBounded) {
  // A robot driving back and forth for 50 bins: open entries never exceed one or two bins' worth of cells.
  auto cfg = smallGrid();
  Gridifier g(cfg, wallMap());
  std::size_t max_open = 0, emitted = 0;
  for (int k = 0; k < 50 * 200; ++k) {
    const double t = k * 0.5;
    const double x = 1.0 + 3.0 * (0.5 + 0.5 * std::sin(t / 40.0));
    g.addPose(t, x, 3.0);
    if (k % 7 == 0) g.addDetection(t, x + 0.3, 3.2);
    if (k % 100 == 0) emitted += g.flush(t).size();
    max_open = std::max(max_open, g.openEntries());
  }
  emitted += g.finish().size();
  EXPECT_GT(emitted, 50u);
  EXPECT_LE(max_open, 2u * 100u);  // at most two bins x 100 cells
}

TEST(CopaGridifier, RejectsBadInput) {
  EXPECT_THROW(Gridifier(GridConfig{}), std::invalid_argument);  // nx = ny = 0
  Gridifier g(smallGrid());
  g.addPose(10.0, 1.0, 1.0);
  EXPECT_THROW(g.addPose(5.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(g.addDetection(std::nan(""), 1.0, 1.0), std::invalid_argument);
}
