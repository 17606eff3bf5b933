// Service-disturbance benchmark (Stüde 2024, §4.3.5, eq. 4.22, following Vintr et al. 2020): patrol paths are
// planned with Dijkstra on an 8-connected (Moore) grid whose edge costs grow with a model's predicted people rate;
// a robot driving a path at constant speed "encounters" the people within a radius. Paths are ranked by planned
// cost, and E(⌊n ρ⌋) sums the encounters of the ⌊n ρ⌋ cheapest ones.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <vector>

#include "cairn/copa_map/gridifier.hpp"

namespace cairn::copa_map {

struct PlanningGrid {
  int nx = 0, ny = 0;
  double origin_x = 0, origin_y = 0, cell = 0.5;
  std::vector<std::uint8_t> blocked;  // nx*ny, 1 = not traversable
  bool free(int ix, int iy) const {
    return ix >= 0 && iy >= 0 && ix < nx && iy < ny && !blocked[static_cast<std::size_t>(iy) * nx + ix];
  }
  Eigen::Vector2d centre(int ix, int iy) const { return {origin_x + (ix + 0.5) * cell, origin_y + (iy + 0.5) * cell}; }
  bool cellOf(const Eigen::Vector2d& p, int& ix, int& iy) const;
};

// A planning cell is blocked when any occupied map cell lies inside it.
PlanningGrid makePlanningGrid(const OccupancyMap& map, double cell, double x0, double y0, double x1, double y1);

struct PlannedPath {
  bool found = false;
  double cost = 0;    // Σ edge length * (1 + cost_per_metre(cell))
  double length = 0;  // m
  std::vector<Eigen::Vector2d> points;  // cell centres from start to goal
};

// Dijkstra on the Moore neighbourhood; the edge into cell c costs |edge| * (1 + extra(c)), extra >= 0.
PlannedPath planPath(const PlanningGrid& grid, const Eigen::Vector2d& start, const Eigen::Vector2d& goal,
                     const std::function<double(int, int)>& extra);

// Expected encounters of a robot driving `path` at `speed` [m/s] from time t0 (in time bins of `bin_seconds`):
// Σ over time steps dt of Σ_{cells within radius} rate(cell, t) * dt / bin_seconds, with rate in people per bin.
double pathEncounters(const std::vector<Eigen::Vector2d>& path, double t0, double speed, double bin_seconds,
                      double radius, double cell, const std::function<double(double, double, double)>& rate);

// E(⌊n ρ⌋) (eq. 4.22): encounters of the ⌊n ρ⌋ lowest-cost paths.
double serviceDisturbance(const std::vector<double>& costs, const std::vector<double>& encounters, double rho);

}  // namespace cairn::copa_map
