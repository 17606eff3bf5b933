#include "cairn/sim/raycast.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cairn::sim {

double raySegment(Vec2 o, Vec2 d, Vec2 a, Vec2 b) {
  const Vec2 e = b - a;
  const double denom = cross(d, e);
  if (std::abs(denom) < 1e-12) return -1.0;  // parallel (grazing hits are measure-zero)
  const Vec2 ao = a - o;
  const double t = cross(ao, e) / denom;
  const double u = cross(ao, d) / denom;
  if (t < 0.0 || u < 0.0 || u > 1.0) return -1.0;
  return t;
}

double rayCircle(Vec2 o, Vec2 d, Vec2 c, double r) {
  const Vec2 m = o - c;
  const double b = dot(m, d);
  const double cc = dot(m, m) - r * r;
  if (cc <= 0.0) return -1.0;  // origin inside
  if (b > 0.0) return -1.0;    // pointing away
  const double disc = b * b - cc;
  if (disc < 0.0) return -1.0;
  return -b - std::sqrt(disc);
}

namespace {
// Liang–Barsky clip of segment a-b against the box [x0,x1]x[y0,y1]; true if any part lies inside.
bool segmentTouchesBox(Vec2 a, Vec2 b, double x0, double y0, double x1, double y1) {
  double t0 = 0.0, t1 = 1.0;
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a.x - x0, x1 - a.x, a.y - y0, y1 - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
    } else {
      const double r = q[i] / p[i];
      if (p[i] < 0.0) t0 = std::max(t0, r);
      else t1 = std::min(t1, r);
      if (t0 > t1) return false;
    }
  }
  return true;
}

double pointSegmentDistance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 e = b - a;
  const double l2 = dot(e, e);
  double u = l2 > 0 ? dot(p - a, e) / l2 : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  return norm(p - (a + u * e));
}
}  // namespace

SegmentGrid::SegmentGrid(std::vector<Segment> segments, double cell_size) : segments_(std::move(segments)) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Vec2 lo{inf, inf}, hi{-inf, -inf};
  double total_len = 0.0;
  for (const auto& s : segments_) {
    lo = {std::min({lo.x, s.a.x, s.b.x}), std::min({lo.y, s.a.y, s.b.y})};
    hi = {std::max({hi.x, s.a.x, s.b.x}), std::max({hi.y, s.a.y, s.b.y})};
    total_len += norm(s.b - s.a);
  }
  if (segments_.empty()) lo = hi = {0, 0};
  if (cell_size <= 0.0) {
    // About one cell per metre of wall, but not finer than 0.25 m and at most ~1M cells (and at most ~1000
    // along either side: a long thin world, e.g. one wall 1e12 m long, would otherwise need billions).
    const double area = std::max(1.0, (hi.x - lo.x) * (hi.y - lo.y));
    cell_size = std::max({0.25, std::sqrt(area / 1.0e6), std::max(hi.x - lo.x, hi.y - lo.y) / 1000.0,
                          std::min(1.0, 0.5 * total_len / std::max<std::size_t>(1, segments_.size()))});
  }
  cell_ = cell_size;
  inv_cell_ = 1.0 / cell_;
  min_ = {lo.x - cell_, lo.y - cell_};
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x - min_.x) * inv_cell_)) + 1);
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y - min_.y) * inv_cell_)) + 1);

  packed_.reserve(segments_.size());
  for (const auto& s : segments_) packed_.push_back({s.a.x, s.a.y, s.b.x - s.a.x, s.b.y - s.a.y, s.reflectivity});

  // two passes: count, then fill (CSR layout, cache friendly)
  const std::size_t ncells = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  std::vector<std::uint32_t> count(ncells + 1, 0);
  auto forEachCell = [&](const Segment& s, auto&& f) {
    const int cx0 = static_cast<int>((std::min(s.a.x, s.b.x) - min_.x) * inv_cell_);
    const int cx1 = static_cast<int>((std::max(s.a.x, s.b.x) - min_.x) * inv_cell_);
    const int cy0 = static_cast<int>((std::min(s.a.y, s.b.y) - min_.y) * inv_cell_);
    const int cy1 = static_cast<int>((std::max(s.a.y, s.b.y) - min_.y) * inv_cell_);
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) {
        const double x0 = min_.x + cx * cell_, y0 = min_.y + cy * cell_;
        // a small margin so that segments on a cell border land in both cells
        if (segmentTouchesBox(s.a, s.b, x0 - 1e-9, y0 - 1e-9, x0 + cell_ + 1e-9, y0 + cell_ + 1e-9))
          f(static_cast<std::size_t>(cy) * nx_ + cx);
      }
  };
  for (const auto& s : segments_) forEachCell(s, [&](std::size_t c) { ++count[c + 1]; });
  cell_start_.assign(ncells + 1, 0);
  for (std::size_t c = 0; c < ncells; ++c) cell_start_[c + 1] = cell_start_[c] + count[c + 1];
  cell_items_.resize(cell_start_.back());
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::uint32_t i = 0; i < segments_.size(); ++i)
    forEachCell(segments_[i], [&](std::size_t c) { cell_items_[fill[c]++] = i; });
}

RayHit SegmentGrid::cast(Vec2 o, Vec2 d, double max_range) const {
  RayHit best;
  best.range = max_range;
  // Clip the ray to the grid box.
  const double gx1 = min_.x + nx_ * cell_, gy1 = min_.y + ny_ * cell_;
  double t_enter = 0.0, t_leave = max_range;
  {
    const double p[4] = {-d.x, d.x, -d.y, d.y};
    const double q[4] = {o.x - min_.x, gx1 - o.x, o.y - min_.y, gy1 - o.y};
    for (int i = 0; i < 4; ++i) {
      if (p[i] == 0.0) {
        if (q[i] < 0.0) return best;
      } else {
        const double r = q[i] / p[i];
        if (p[i] < 0.0) t_enter = std::max(t_enter, r);
        else t_leave = std::min(t_leave, r);
      }
    }
    if (t_enter > t_leave) return best;
  }
  const double px = o.x + t_enter * d.x, py = o.y + t_enter * d.y;
  int cx = std::clamp(static_cast<int>((px - min_.x) * inv_cell_), 0, nx_ - 1);
  int cy = std::clamp(static_cast<int>((py - min_.y) * inv_cell_), 0, ny_ - 1);
  const int step_x = d.x > 0 ? 1 : -1, step_y = d.y > 0 ? 1 : -1;
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double tdx = d.x != 0.0 ? cell_ / std::abs(d.x) : inf;
  const double tdy = d.y != 0.0 ? cell_ / std::abs(d.y) : inf;
  double tmx = d.x != 0.0 ? ((min_.x + (cx + (step_x > 0 ? 1 : 0)) * cell_) - o.x) / d.x : inf;
  double tmy = d.y != 0.0 ? ((min_.y + (cy + (step_y > 0 ? 1 : 0)) * cell_) - o.y) / d.y : inf;

  double best_t = max_range;
  float best_refl = 0.0F;
  bool hit = false;
  for (;;) {
    const std::size_t c = static_cast<std::size_t>(cy) * nx_ + cx;
    for (std::uint32_t k = cell_start_[c], end = cell_start_[c + 1]; k < end; ++k) {
      const Packed& s = packed_[cell_items_[k]];
      const double denom = d.x * s.ey - d.y * s.ex;
      if (denom == 0.0) continue;
      const double aox = s.ax - o.x, aoy = s.ay - o.y;
      const double inv = 1.0 / denom;
      const double t = (aox * s.ey - aoy * s.ex) * inv;
      if (t < 0.0 || t >= best_t) continue;
      const double u = (aox * d.y - aoy * d.x) * inv;
      if (u < 0.0 || u > 1.0) continue;
      best_t = t;
      best_refl = s.reflectivity;
      hit = true;
    }
    const double t_exit = std::min(tmx, tmy);
    if (best_t <= t_exit || t_exit > t_leave) break;
    if (tmx < tmy) {
      cx += step_x;
      tmx += tdx;
      if (cx < 0 || cx >= nx_) break;
    } else {
      cy += step_y;
      tmy += tdy;
      if (cy < 0 || cy >= ny_) break;
    }
  }
  if (hit) {
    best.hit = true;
    best.range = best_t;
    best.reflectivity = best_refl;
  }
  return best;
}

bool SegmentGrid::intersectsDisc(Vec2 c, double r) const { return distanceToNearest(c, r) < r; }

double SegmentGrid::distanceToNearest(Vec2 p, double max_dist) const {
  double best = max_dist;
  const int cx0 = std::max(0, static_cast<int>((p.x - max_dist - min_.x) * inv_cell_));
  const int cx1 = std::min(nx_ - 1, static_cast<int>((p.x + max_dist - min_.x) * inv_cell_));
  const int cy0 = std::max(0, static_cast<int>((p.y - max_dist - min_.y) * inv_cell_));
  const int cy1 = std::min(ny_ - 1, static_cast<int>((p.y + max_dist - min_.y) * inv_cell_));
  for (int cy = cy0; cy <= cy1; ++cy)
    for (int cx = cx0; cx <= cx1; ++cx) {
      const std::size_t c = static_cast<std::size_t>(cy) * nx_ + cx;
      for (std::uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const Segment& s = segments_[cell_items_[k]];
        best = std::min(best, pointSegmentDistance(p, s.a, s.b));
      }
    }
  return best;
}

RayHit castNaive(const std::vector<Segment>& segments, Vec2 o, Vec2 d, double max_range) {
  RayHit best;
  best.range = max_range;
  for (const auto& s : segments) {
    const double t = raySegment(o, d, s.a, s.b);
    if (t >= 0.0 && t < best.range) {
      best.range = t;
      best.reflectivity = s.reflectivity;
      best.hit = true;
    }
  }
  return best;
}

}  // namespace cairn::sim
