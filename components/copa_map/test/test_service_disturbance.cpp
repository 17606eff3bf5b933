#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "cairn/copa_map/service_disturbance.hpp"

using namespace cairn::copa_map;

namespace {
// 20 m x 10 m room, 0.1 m map, with a wall across x = 10 m except for two doors (y in [1,2] and [8,9]).
OccupancyMap room() {
  OccupancyMap m;
  m.width = 200;
  m.height = 100;
  m.resolution = 0.1;
  m.occupied.assign(200 * 100, 0);
  for (int cy = 0; cy < 100; ++cy) {
    const double y = (cy + 0.5) * 0.1;
    if ((y > 1.0 && y < 2.0) || (y > 8.0 && y < 9.0)) continue;
    for (int cx = 99; cx <= 101; ++cx) m.occupied[cy * 200 + cx] = 1;
  }
  return m;
}
}  // namespace

TEST(CopaServiceDisturbance, DijkstraAvoidsCrowdsAndFewerEncountersThanShortestPath) {
  const OccupancyMap m = room();
  const PlanningGrid g = makePlanningGrid(m, 0.5, 0.0, 0.0, 20.0, 10.0);
  EXPECT_FALSE(g.free(19, 10));  // the wall cell column x in [9.5, 10)
  EXPECT_TRUE(g.free(19, 3));    // lower door
  const Eigen::Vector2d a(2.0, 3.0), b(18.0, 3.0);
  // Crowd at the lower door: 50 people per bin in the cells around (10, 1.5).
  auto crowd = [](double x, double y, double) { return (std::abs(x - 10.0) < 3.0 && y < 4.0) ? 50.0 : 0.0; };
  const PlannedPath shortest = planPath(g, a, b, [](int, int) { return 0.0; });
  ASSERT_TRUE(shortest.found);
  const PlannedPath aware = planPath(g, a, b, [&](int ix, int iy) {
    const Eigen::Vector2d c = g.centre(ix, iy);
    return 10.0 * crowd(c.x(), c.y(), 0) / 50.0;
  });
  ASSERT_TRUE(aware.found);
  double max_y = 0, max_y_short = 0;
  for (const auto& p : aware.points) max_y = std::max(max_y, p.y());
  for (const auto& p : shortest.points) max_y_short = std::max(max_y_short, p.y());
  EXPECT_GT(max_y, 8.0);        // detour through the upper door
  EXPECT_LT(max_y_short, 4.0);  // the shortest path takes the lower door
  EXPECT_GT(aware.length, shortest.length);
  const double e_short = pathEncounters(shortest.points, 0.0, 0.5, 3600.0, 1.0, 0.5, crowd);
  const double e_aware = pathEncounters(aware.points, 0.0, 0.5, 3600.0, 1.0, 0.5, crowd);
  EXPECT_GT(e_short, 0.0);
  EXPECT_LT(e_aware, 0.1 * e_short);
  // Blocked goal: no path.
  EXPECT_FALSE(planPath(g, a, Eigen::Vector2d(9.8, 5.0), [](int, int) { return 0.0; }).found);
}

TEST(CopaServiceDisturbance, Equation422SumsTheCheapestPaths) {
  const std::vector<double> cost{3, 1, 2, 4}, enc{30, 10, 20, 40};
  EXPECT_DOUBLE_EQ(serviceDisturbance(cost, enc, 0.5), 30.0);  // two cheapest: 10 + 20
  EXPECT_DOUBLE_EQ(serviceDisturbance(cost, enc, 1.0), 100.0);
  EXPECT_DOUBLE_EQ(serviceDisturbance(cost, enc, 0.0), 0.0);
}

TEST(CopaServiceDisturbance, EncountersScaleWithDwellTime) {
  // Straight 10 m path through a uniform field of 3.6 people per bin (1 h): at 0.5 m/s the robot needs 20 s;
  // cells within 1 m at 0.5 m spacing: 13 (centre, 4 at 0.5, 4 at 1.0, 4 diagonals at 0.71).
  std::vector<Eigen::Vector2d> path;
  for (int i = 0; i <= 20; ++i) path.emplace_back(0.25 + 0.5 * i, 0.25);
  const double e = pathEncounters(path, 0.0, 0.5, 3600.0, 1.0, 0.5, [](double, double, double) { return 3.6; });
  EXPECT_NEAR(e, 13 * 3.6 * 20.0 / 3600.0, 1e-9);
}
