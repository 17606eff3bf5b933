#include "cairn/copa_map/gridifier.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cairn::copa_map {

bool OccupancyMap::occupiedAt(double x, double y) const {
  const int cx = static_cast<int>(std::floor((x - origin_x) / resolution));
  const int cy = static_cast<int>(std::floor((y - origin_y) / resolution));
  return occupiedCell(cx, cy);
}

bool OccupancyMap::lineOfSight(double x0, double y0, double x1, double y1) const {
  // Amanatides & Woo voxel traversal in map-cell coordinates.
  const double fx0 = (x0 - origin_x) / resolution, fy0 = (y0 - origin_y) / resolution;
  const double fx1 = (x1 - origin_x) / resolution, fy1 = (y1 - origin_y) / resolution;
  int cx = static_cast<int>(std::floor(fx0)), cy = static_cast<int>(std::floor(fy0));
  const int ex = static_cast<int>(std::floor(fx1)), ey = static_cast<int>(std::floor(fy1));
  const double dx = fx1 - fx0, dy = fy1 - fy0;
  const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  const double tdx = dx != 0 ? std::abs(1.0 / dx) : inf;
  const double tdy = dy != 0 ? std::abs(1.0 / dy) : inf;
  double tmx = dx != 0 ? ((dx > 0 ? (cx + 1 - fx0) : (fx0 - cx)) * tdx) : inf;
  double tmy = dy != 0 ? ((dy > 0 ? (cy + 1 - fy0) : (fy0 - cy)) * tdy) : inf;
  const int max_steps = std::abs(ex - cx) + std::abs(ey - cy) + 2;
  for (int step = 0; step < max_steps && !(cx == ex && cy == ey); ++step) {
    if (tmx < tmy) {
      tmx += tdx;
      cx += sx;
    } else {
      tmy += tdy;
      cy += sy;
    }
    if (occupiedCell(cx, cy)) return false;
  }
  return true;
}

Gridifier::Gridifier(GridConfig config, std::shared_ptr<const OccupancyMap> map)
    : config_(config), map_(std::move(map)) {
  if (!(config_.cell_size > 0) || !(config_.time_bin > 0) || config_.nx <= 0 || config_.ny <= 0 ||
      !(config_.fov_radius >= 0) || !(config_.rate_unit > 0) || !(config_.max_pose_gap >= 0))
    throw std::invalid_argument("Gridifier: cell_size, time_bin, nx, ny, rate_unit must be positive");
}

std::int64_t Gridifier::binOf(double t) const {
  return static_cast<std::int64_t>(std::floor((t - config_.t_origin) / config_.time_bin));
}

std::vector<int> Gridifier::visibleCells(double x, double y) const {
  std::vector<int> out;
  const double r = config_.fov_radius, cs = config_.cell_size;
  const int ix0 = std::max(0, static_cast<int>(std::floor((x - r - config_.origin_x) / cs)));
  const int ix1 = std::min(config_.nx - 1, static_cast<int>(std::floor((x + r - config_.origin_x) / cs)));
  const int iy0 = std::max(0, static_cast<int>(std::floor((y - r - config_.origin_y) / cs)));
  const int iy1 = std::min(config_.ny - 1, static_cast<int>(std::floor((y + r - config_.origin_y) / cs)));
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      const double cx = config_.origin_x + (ix + 0.5) * cs, cy = config_.origin_y + (iy + 0.5) * cs;
      if ((cx - x) * (cx - x) + (cy - y) * (cy - y) > r * r) continue;
      if (map_ && !map_->lineOfSight(x, y, cx, cy)) continue;  // FOV circle pruned by ray casting (§4.2.2)
      out.push_back(iy * config_.nx + ix);
    }
  }
  return out;
}

void Gridifier::creditDuration(double t0, double t1, const std::vector<int>& cells) {
  // Split [t0, t1) at bin boundaries; every visible cell accumulates the overlap (Δ_i, §4.2.2).
  while (t1 > t0) {
    const std::int64_t b = binOf(t0);
    const double bin_end = config_.t_origin + static_cast<double>(b + 1) * config_.time_bin;
    const double seg_end = std::min(t1, bin_end);
    if (b >= emitted_up_to_) {
      BinMap& bm = bins_[b];
      for (int c : cells) {
        Accumulator& acc = bm[c];
        acc.duration += seg_end - t0;
        if (!acc.seen.empty() && acc.seen.back().second >= t0) {
          acc.seen.back().second = seg_end;  // contiguous with the last stretch
        } else {
          acc.seen.emplace_back(t0, seg_end);
        }
      }
    }
    t0 = seg_end;
  }
}

void Gridifier::addPose(double t, double x, double y) {
  if (!std::isfinite(t) || !std::isfinite(x) || !std::isfinite(y))
    throw std::invalid_argument("Gridifier::addPose: non-finite pose");
  if (have_pose_) {
    if (t < last_t_) throw std::invalid_argument("Gridifier::addPose: time went backwards");
    creditDuration(last_t_, std::min(t, last_t_ + config_.max_pose_gap), last_visible_);
  }
  // Re-cast only when the robot moved (cheap cache for stops).
  if (!have_pose_ || x != last_x_ || y != last_y_) last_visible_ = visibleCells(x, y);
  have_pose_ = true;
  last_t_ = t;
  last_x_ = x;
  last_y_ = y;
}

void Gridifier::addDetection(double t, double x, double y) {
  if (!std::isfinite(t) || !std::isfinite(x) || !std::isfinite(y))
    throw std::invalid_argument("Gridifier::addDetection: non-finite detection");
  const int ix = static_cast<int>(std::floor((x - config_.origin_x) / config_.cell_size));
  const int iy = static_cast<int>(std::floor((y - config_.origin_y) / config_.cell_size));
  if (ix < 0 || iy < 0 || ix >= config_.nx || iy >= config_.ny) {
    ++stats_.detections_outside_grid;
    return;
  }
  const std::int64_t b = binOf(t);
  if (b < emitted_up_to_) {
    ++stats_.detections_late;
    return;
  }
  const int idx = iy * config_.nx + ix;
  bool seen = have_pose_ && t >= last_t_ && t <= last_t_ + config_.max_pose_gap &&
              std::binary_search(last_visible_.begin(), last_visible_.end(), idx);  // the stretch not yet credited
  auto bin = bins_.find(b);
  Accumulator* acc = nullptr;
  if (bin != bins_.end()) {
    auto cell = bin->second.find(idx);
    if (cell != bin->second.end()) acc = &cell->second;
  }
  if (!seen && acc)
    for (const auto& [from, to] : acc->seen) seen = seen || (t >= from && t < to);  // [from, to): at `to` it moved
  if (!seen) {
    ++stats_.detections_unobserved;
    return;
  }
  if (!acc) acc = &bins_[b][idx];
  acc->count += 1.0;
}

void Gridifier::emitBin(std::int64_t bin, BinMap& cells, std::vector<GridCell>& out) {
  std::vector<std::pair<int, Accumulator>> sorted(cells.begin(), cells.end());
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [idx, acc] : sorted) {
    if (acc.duration < config_.min_duration || acc.duration <= 0) {
      stats_.detections_unobserved += static_cast<std::uint64_t>(acc.count);
      if (acc.duration > 0) ++stats_.cells_dropped_short;
      continue;
    }
    GridCell c;
    c.ix = idx % config_.nx;
    c.iy = idx / config_.nx;
    c.bin = bin;
    c.x1 = config_.origin_x + (c.ix + 0.5) * config_.cell_size;
    c.x2 = config_.origin_y + (c.iy + 0.5) * config_.cell_size;
    c.t = static_cast<double>(bin);
    c.count = acc.count;
    c.duration = std::min(acc.duration, config_.time_bin);
    // Stüde eq. 4.6: y_i = c_i / Δ_i (rate per rate_unit seconds); empty cells get rate_min.
    c.rate = c.count > 0 ? c.count / (c.duration / config_.rate_unit) : config_.rate_min;
    stats_.detections_counted += static_cast<std::uint64_t>(acc.count);
    out.push_back(c);
  }
}

std::vector<GridCell> Gridifier::flush(double t) {
  std::vector<GridCell> out;
  const double horizon = have_pose_ ? std::min(t, last_t_) : t;
  const std::int64_t first_open = binOf(horizon);  // bins < first_open have ended
  std::vector<std::int64_t> done;
  for (const auto& kv : bins_)
    if (kv.first < first_open) done.push_back(kv.first);
  std::sort(done.begin(), done.end());
  for (std::int64_t b : done) {
    emitBin(b, bins_[b], out);
    bins_.erase(b);
  }
  emitted_up_to_ = std::max(emitted_up_to_, first_open);
  return out;
}

std::vector<GridCell> Gridifier::finish() {
  std::vector<GridCell> out;
  std::vector<std::int64_t> all;
  for (const auto& kv : bins_) all.push_back(kv.first);
  std::sort(all.begin(), all.end());
  for (std::int64_t b : all) emitBin(b, bins_[b], out);
  if (!all.empty()) emitted_up_to_ = std::max(emitted_up_to_, all.back() + 1);
  bins_.clear();
  return out;
}

std::size_t Gridifier::openEntries() const {
  std::size_t n = 0;
  for (const auto& kv : bins_) n += kv.second.size();
  return n;
}

}  // namespace cairn::copa_map
