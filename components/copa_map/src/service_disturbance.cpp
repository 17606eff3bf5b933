#include "cairn/copa_map/service_disturbance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <stdexcept>

namespace cairn::copa_map {

bool PlanningGrid::cellOf(const Eigen::Vector2d& p, int& ix, int& iy) const {
  ix = static_cast<int>(std::floor((p.x() - origin_x) / cell));
  iy = static_cast<int>(std::floor((p.y() - origin_y) / cell));
  return ix >= 0 && iy >= 0 && ix < nx && iy < ny;
}

PlanningGrid makePlanningGrid(const OccupancyMap& map, double cell, double x0, double y0, double x1, double y1) {
  if (!(cell > 0) || !(x1 > x0) || !(y1 > y0)) throw std::invalid_argument("makePlanningGrid: empty area");
  PlanningGrid g;
  g.cell = cell;
  g.origin_x = x0;
  g.origin_y = y0;
  g.nx = static_cast<int>(std::ceil((x1 - x0) / cell));
  g.ny = static_cast<int>(std::ceil((y1 - y0) / cell));
  g.blocked.assign(static_cast<std::size_t>(g.nx) * g.ny, 0);
  const int sub = std::max(1, static_cast<int>(std::lround(cell / map.resolution)));
  for (int iy = 0; iy < g.ny; ++iy)
    for (int ix = 0; ix < g.nx; ++ix)
      for (int a = 0; a < sub && !g.blocked[static_cast<std::size_t>(iy) * g.nx + ix]; ++a)
        for (int b = 0; b < sub; ++b) {
          const double x = x0 + ix * cell + (a + 0.5) * cell / sub, y = y0 + iy * cell + (b + 0.5) * cell / sub;
          if (map.occupiedAt(x, y)) {
            g.blocked[static_cast<std::size_t>(iy) * g.nx + ix] = 1;
            break;
          }
        }
  return g;
}

PlannedPath planPath(const PlanningGrid& grid, const Eigen::Vector2d& start, const Eigen::Vector2d& goal,
                     const std::function<double(int, int)>& extra) {
  PlannedPath out;
  int sx, sy, gx, gy;
  if (!grid.cellOf(start, sx, sy) || !grid.cellOf(goal, gx, gy) || !grid.free(sx, sy) || !grid.free(gx, gy))
    return out;
  const int n = grid.nx * grid.ny;
  std::vector<double> dist(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
  std::vector<int> prev(static_cast<std::size_t>(n), -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
  const int s = sy * grid.nx + sx, goal_idx = gy * grid.nx + gx;
  dist[static_cast<std::size_t>(s)] = 0;
  pq.push({0.0, s});
  while (!pq.empty()) {
    const auto [d, u] = pq.top();
    pq.pop();
    if (d > dist[static_cast<std::size_t>(u)]) continue;
    if (u == goal_idx) break;
    const int ux = u % grid.nx, uy = u / grid.nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const int vx = ux + dx, vy = uy + dy;
        if (!grid.free(vx, vy)) continue;
        if (dx && dy && (!grid.free(ux + dx, uy) || !grid.free(ux, uy + dy))) continue;  // no corner cutting
        const double len = grid.cell * ((dx && dy) ? std::sqrt(2.0) : 1.0);
        const double nd = d + len * (1.0 + std::max(0.0, extra(vx, vy)));
        const int v = vy * grid.nx + vx;
        if (nd < dist[static_cast<std::size_t>(v)]) {
          dist[static_cast<std::size_t>(v)] = nd;
          prev[static_cast<std::size_t>(v)] = u;
          pq.push({nd, v});
        }
      }
  }
  if (!std::isfinite(dist[static_cast<std::size_t>(goal_idx)])) return out;
  out.found = true;
  out.cost = dist[static_cast<std::size_t>(goal_idx)];
  for (int v = goal_idx; v != -1; v = prev[static_cast<std::size_t>(v)]) out.points.push_back(grid.centre(v % grid.nx, v / grid.nx));
  std::reverse(out.points.begin(), out.points.end());
  for (std::size_t i = 1; i < out.points.size(); ++i) out.length += (out.points[i] - out.points[i - 1]).norm();
  return out;
}

double pathEncounters(const std::vector<Eigen::Vector2d>& path, double t0, double speed, double bin_seconds,
                      double radius, double cell, const std::function<double(double, double, double)>& rate) {
  if (path.empty()) return 0.0;
  const double dt = 1.0;  // s
  double t = t0 * bin_seconds, total = 0;
  const int r = static_cast<int>(std::ceil(radius / cell));
  auto visit = [&](const Eigen::Vector2d& p) {
    // Cells whose centre lies within `radius` of the robot (cell grid aligned to the path's cell centres).
    for (int a = -r; a <= r; ++a)
      for (int b = -r; b <= r; ++b) {
        const Eigen::Vector2d c = p + Eigen::Vector2d(a * cell, b * cell);
        if ((c - p).norm() > radius + 1e-9) continue;
        total += rate(c.x(), c.y(), t / bin_seconds) * dt / bin_seconds;
      }
  };
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Eigen::Vector2d a = path[i - 1], b = path[i];
    const double len = (b - a).norm();
    const int steps = std::max(1, static_cast<int>(std::round(len / (speed * dt))));
    for (int k = 0; k < steps; ++k) {
      // Snap to the nearest cell centre of the segment (path points are cell centres).
      visit(k * 2 < steps ? a : b);
      t += len / speed / steps;
    }
  }
  return total;
}

double serviceDisturbance(const std::vector<double>& costs, const std::vector<double>& encounters, double rho) {
  if (costs.size() != encounters.size()) throw std::invalid_argument("serviceDisturbance: size mismatch");
  std::vector<std::size_t> idx(costs.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return costs[a] < costs[b]; });
  const auto k = static_cast<std::size_t>(std::floor(static_cast<double>(costs.size()) * rho + 1e-9));
  double e = 0;
  for (std::size_t i = 0; i < k && i < idx.size(); ++i) e += encounters[idx[i]];  // eq. 4.22
  return e;
}

}  // namespace cairn::copa_map
