#include "cairn/people_tracking/static_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cairn::people_tracking {

Eigen::Vector2i StaticMap::cellOf(const Eigen::Vector2d& p_map) const {
  const Eigen::Vector2d q = (p_map - origin) / resolution;
  return {static_cast<int>(std::floor(q.x())), static_cast<int>(std::floor(q.y()))};
}

bool StaticMap::occupiedWithin(const Eigen::Vector2d& p_tracking, double radius) const {
  if (width <= 0 || height <= 0 || !(resolution > 0.0)) return false;
  const Eigen::Vector2d p_map = map_from_tracking.transform(p_tracking), p = p_map - origin;
  const int r = static_cast<int>(std::ceil(radius / resolution));
  const Eigen::Vector2i c0 = cellOf(p_map);
  for (int y = std::max(0, c0.y() - r); y <= std::min(height - 1, c0.y() + r); ++y)
    for (int x = std::max(0, c0.x() - r); x <= std::min(width - 1, c0.x() + r); ++x) {
      if (!occupied[index(x, y)]) continue;
      const Eigen::Vector2d c((x + 0.5) * resolution, (y + 0.5) * resolution);
      if ((c - p).norm() <= radius) return true;
    }
  return false;
}

StaticMap rasterize(const Scene& scene, double resolution) {
  StaticMap m;
  m.resolution = resolution;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  auto isStatic = [&](int object) { return object < 0 || scene.object_person[static_cast<std::size_t>(object)] < 0; };
  for (const auto& s : scene.segments)
    if (isStatic(s.object)) {
      lo = lo.cwiseMin(s.a).cwiseMin(s.b);
      hi = hi.cwiseMax(s.a).cwiseMax(s.b);
    }
  for (const auto& c : scene.circles)
    if (isStatic(c.object)) {
      const Eigen::Vector2d r = Eigen::Vector2d::Constant(c.radius);
      lo = lo.cwiseMin(c.center - r);
      hi = hi.cwiseMax(c.center + r);
    }
  if (!(lo.x() <= hi.x())) return m;  // no static geometry
  m.origin = lo - Eigen::Vector2d::Constant(resolution);
  m.width = static_cast<int>(std::ceil((hi.x() - m.origin.x()) / resolution)) + 1;
  m.height = static_cast<int>(std::ceil((hi.y() - m.origin.y()) / resolution)) + 1;
  m.occupied.assign(static_cast<std::size_t>(m.width) * static_cast<std::size_t>(m.height), 0);
  auto mark = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2i c = m.cellOf(p);
    if (c.x() >= 0 && c.y() >= 0 && c.x() < m.width && c.y() < m.height) m.occupied[m.index(c.x(), c.y())] = 1;
  };
  const double step = 0.5 * resolution;
  for (const auto& s : scene.segments) {
    if (!isStatic(s.object)) continue;
    const int n = static_cast<int>(std::ceil((s.b - s.a).norm() / step));
    for (int k = 0; k <= n; ++k) mark(s.a + (s.b - s.a) * (n ? double(k) / n : 0.0));
  }
  for (const auto& c : scene.circles) {
    if (!isStatic(c.object)) continue;
    const int n = std::max(8, static_cast<int>(std::ceil(2.0 * M_PI * c.radius / step)));
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * M_PI * k / n;
      mark(c.center + c.radius * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
    mark(c.center);
  }
  return m;
}

}  // namespace cairn::people_tracking
