#include "cairn/people_tracking/motion_evidence.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace cairn::people_tracking {

FreeSpaceMemory::FreeSpaceMemory(double resolution, double size, double margin, double memory,
                                 std::size_t min_free_scans, double surface_gap)
    : resolution_(resolution), size_(size), margin_(margin), memory_(memory), surface_gap_(surface_gap),
      min_free_scans_(static_cast<std::uint16_t>(std::min<std::size_t>(min_free_scans, 65535))) {
  // At most 4000 x 4000 cells (128 MB): a 400 m grid at 0.1 m, or 80 m at 0.02 m.
  if (!(resolution_ > 0.0) || !(size_ >= 4.0 * resolution_) || !(size_ <= 4000.0 * resolution_) ||
      !(margin_ >= 0.0) || !(memory_ >= 0.0) || min_free_scans == 0 || !(surface_gap_ >= 0.0) ||
      !std::isfinite(surface_gap_))
    throw InputError("free-space memory (motion.memory_*): resolution must be > 0, size in [4, 4000] cells, margin, "
                     "memory and surface_gap >= 0, min_free_scans >= 1");
}

void FreeSpaceMemory::clear() {
  std::fill(grid_.begin(), grid_.end(), Cell{});
  empty_ = true;
}

long FreeSpaceMemory::cellIndex(const Eigen::Vector2d& p) const {
  const double fx = std::floor((p.x() - origin_.x()) / resolution_);
  const double fy = std::floor((p.y() - origin_.y()) / resolution_);
  if (!(fx >= 0.0 && fy >= 0.0 && fx < cells_ && fy < cells_)) return -1;
  return static_cast<long>(fy) * cells_ + static_cast<long>(fx);
}

void FreeSpaceMemory::follow(const Eigen::Vector2d& sensor) {
  const Eigen::Vector2d rel = sensor - origin_;
  if (cells_ > 0 && rel.minCoeff() >= size_ / 4.0 && rel.maxCoeff() <= 3.0 * size_ / 4.0) return;
  const long n = std::lround(std::ceil(size_ / resolution_));
  // Whole cells, so that the remembered cells move without resampling.
  const Eigen::Vector2d origin = ((sensor.array() - size_ / 2.0) / resolution_).floor().matrix() * resolution_;
  std::vector<Cell> moved(static_cast<std::size_t>(n * n));
  const Eigen::Vector2d shift = (origin - origin_) / resolution_;
  if (cells_ > 0 && shift.cwiseAbs().maxCoeff() < cells_) {  // else nothing remembered stays inside
    const long dx = std::lround(shift.x()), dy = std::lround(shift.y());
    for (long y = std::max(0L, -dy); y < n && y + dy < cells_; ++y)
      for (long x = std::max(0L, -dx); x < n && x + dx < cells_; ++x)
        moved[static_cast<std::size_t>(y * n + x)] = grid_[static_cast<std::size_t>((y + dy) * cells_ + x + dx)];
  }
  cells_ = static_cast<int>(n);
  origin_ = origin;
  grid_.swap(moved);
  near_now_.assign((grid_.size() + 63) / 64, 0);
  crossed_now_.assign(near_now_.size(), 0);
}

void FreeSpaceMemory::count(std::uint16_t& counter, Cell& cell) {
  if (counter == std::numeric_limits<std::uint16_t>::max()) {
    // Both halved: the ratio stays, older scans weigh less.
    cell.near_scans = static_cast<std::uint16_t>(cell.near_scans / 2);
    cell.free_scans = static_cast<std::uint16_t>(cell.free_scans / 2);
  }
  ++counter;
}

template <typename Visit>
void FreeSpaceMemory::cross(const Eigen::Vector2d& from, double angle, double length, Visit&& visit) const {
  // Amanatides & Woo: from cell to cell along the ray; a cell counts once the ray has left it before `length`.
  const double dx = std::cos(angle), dy = std::sin(angle);
  const double px = (from.x() - origin_.x()) / resolution_, py = (from.y() - origin_.y()) / resolution_;
  long ix = static_cast<long>(std::floor(px)), iy = static_cast<long>(std::floor(py));
  const long sx = dx > 0.0 ? 1 : -1, sy = dy > 0.0 ? 1 : -1;
  constexpr double kFar = std::numeric_limits<double>::infinity();
  const double step_x = dx != 0.0 ? resolution_ / std::abs(dx) : kFar;
  const double step_y = dy != 0.0 ? resolution_ / std::abs(dy) : kFar;
  double next_x = dx > 0.0 ? (static_cast<double>(ix + 1) - px) * step_x
                           : (dx < 0.0 ? (px - static_cast<double>(ix)) * step_x : kFar);
  double next_y = dy > 0.0 ? (static_cast<double>(iy + 1) - py) * step_y
                           : (dy < 0.0 ? (py - static_cast<double>(iy)) * step_y : kFar);
  while (ix >= 0 && iy >= 0 && ix < cells_ && iy < cells_ && std::min(next_x, next_y) <= length) {
    visit(static_cast<std::size_t>(iy * cells_ + ix));
    if (next_x < next_y) {
      next_x += step_x;
      ix += sx;
    } else {
      next_y += step_y;
      iy += sy;
    }
  }
}

void FreeSpaceMemory::add(const LaserScan& scan, const Pose2& sensor_pose) {
  if (!enabled()) return;
  // A pose the grid cannot hold (not finite, or beyond 1e9 m) gives no information; nothing else is affected.
  if (!(std::abs(sensor_pose.x) < 1e9 && std::abs(sensor_pose.y) < 1e9 && std::isfinite(sensor_pose.theta))) return;
  if (!empty_ && scan.stamp < newest_) clear();
  if (empty_) epoch_ = scan.stamp;
  empty_ = false;
  newest_ = scan.stamp;
  const Eigen::Vector2d sensor(sensor_pose.x, sensor_pose.y);
  follow(sensor);
  // This scan's marks: one bit per cell, small enough to stay in cache while the rays are walked.
  std::fill(near_now_.begin(), near_now_.end(), 0);
  std::fill(crossed_now_.begin(), crossed_now_.end(), 0);
  const std::size_t n = scan.ranges.size();
  const bool full_circle = scan.fullCircle();
  const Eigen::Matrix2d R = sensor_pose.rotation();
  auto nearReturn = [&](const Eigen::Vector2d& p) {
    const long c = cellIndex(p);
    if (c < 0) return;
    const long x = c % cells_, y = c / cells_;
    for (long yy = std::max(0L, y - 1); yy <= std::min<long>(cells_ - 1, y + 1); ++yy)
      for (long xx = std::max(0L, x - 1); xx <= std::min<long>(cells_ - 1, x + 1); ++xx) {
        set(near_now_, static_cast<std::size_t>(yy * cells_ + xx));
      }
  };
  // The cells next to a return of this scan, or next to the surface between two consecutive returns less than
  // surface_gap apart, are not free in it, whatever crosses them: a wall seen at a grazing angle has returns
  // decimetres apart, and the beams graze the cells between them before they hit the wall farther on.
  Eigen::Vector2d previous;
  bool have_previous = false;
  for (std::size_t k = 0; k <= n; ++k) {
    if (k == n && !full_circle) break;
    const std::size_t i = k % n;
    if (!scan.valid(i)) {
      have_previous = false;
      continue;
    }
    const Eigen::Vector2d p = R * scan.point(i) + sensor;
    if (k < n) nearReturn(p);
    if (have_previous) {
      const double gap = (p - previous).norm();
      if (gap <= surface_gap_) {
        const auto steps = static_cast<int>(std::ceil(gap / (0.5 * resolution_)));
        for (int j = 1; j < steps; ++j) nearReturn(previous + (p - previous) * (static_cast<double>(j) / steps));
      }
    }
    previous = p;
    have_previous = true;
  }
  const auto stamp = static_cast<float>(scan.stamp - epoch_);
  const double step = std::abs(scan.angle_increment);
  for (std::size_t i = 0; i < n; ++i) {
    double length;
    if (scan.valid(i)) {
      length = scan.ranges[i] - margin_;
    } else if (scan.beyondRange(i)) {
      // No return within range_max: crossed up to it, or up to a neighbour's return (a dropout on a wall).
      length = scan.range_max - margin_;
      const std::size_t before = i > 0 ? i - 1 : (full_circle ? n - 1 : n);
      const std::size_t after = i + 1 < n ? i + 1 : (full_circle ? 0 : n);
      for (const std::size_t j : {before, after})
        if (j < n && scan.valid(j)) length = std::min(length, static_cast<double>(scan.ranges[j]) - margin_);
    } else {
      continue;  // NaN or a too-close echo: no information
    }
    // Followed up to a quarter of the grid's side (10 m by default: the detector's max_range), the distance to the
    // grid's edge the sensor always keeps; farther cells are never asked about, and near the edge they would be
    // moved out soon.
    length = std::min(length, size_ / 4.0);
    // Near the sensor the beams are much closer than a cell: every second beam is enough out to where their
    // spacing reaches a cell, every fourth out to half that distance, and so on. A beam whose index has k trailing
    // zero bits starts where the beams 2^(k+1) apart stop covering every cell (about 2.4x fewer steps at 0.33 deg
    // and 10 m; the cells a skipped stretch passes are crossed by the beams beside it).
    const double start = i == 0 ? 0.0 : resolution_ / (std::ldexp(step, std::countr_zero(i) + 1));
    if (length > start) {
      const double angle = sensor_pose.theta + scan.angle(i);
      const Eigen::Vector2d from = sensor + start * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      cross(from, angle, length - start, [&](std::size_t c) { set(crossed_now_, c); });
    }
  }
  // The counts, in memory order (the rays above touch only the bits).
  for (std::size_t w = 0; w < near_now_.size(); ++w) {
    const std::uint64_t near = near_now_[w], free = crossed_now_[w] & ~near;
    for (std::uint64_t bits = near | free; bits != 0; bits &= bits - 1) {
      const auto b = static_cast<std::size_t>(std::countr_zero(bits));
      Cell& cell = grid_[w * 64 + b];
      if ((near >> b) & 1U) {
        count(cell.near_scans, cell);
      } else {
        count(cell.free_scans, cell);
        cell.last_free = stamp;
      }
    }
  }
}

bool FreeSpaceMemory::seenFree(const Eigen::Vector2d& p, double stamp) const {
  if (empty_ || !enabled()) return false;
  const long c = cellIndex(p);
  if (c < 0) return false;
  const long x = c % cells_, y = c / cells_;
  if (x == 0 || y == 0 || x == cells_ - 1 || y == cells_ - 1) return false;  // its neighbours are not all known
  for (long yy = y - 1; yy <= y + 1; ++yy)
    for (long xx = x - 1; xx <= x + 1; ++xx) {
      const Cell& cell = grid_[static_cast<std::size_t>(yy * cells_ + xx)];
      if (cell.free_scans < min_free_scans_ || cell.free_scans <= cell.near_scans ||
          stamp - (epoch_ + static_cast<double>(cell.last_free)) > memory_)
        return false;
    }
  return true;
}

namespace {
const MotionEvidenceParams& validated(const MotionEvidenceParams& p) {
  if (!(p.window >= 0.0) || !(p.min_age >= 0.0) || !(p.margin >= 0.0) || p.max_scans == 0 || p.min_free_scans == 0)
    throw InputError("motion evidence: window, min_age and margin must be >= 0, max_scans and min_free_scans > 0");
  return p;
}
}  // namespace

MotionEvidence::MotionEvidence(MotionEvidenceParams params)
    : params_(validated(params)),
      memory_(params.memory_resolution, params.memory_size, params.margin, params.memory, params.min_free_scans,
              params.memory_surface_gap) {}

void MotionEvidence::add(const LaserScan& scan, const Pose2& sensor_pose) {
  validateScan(scan);
  memory_.add(scan, sensor_pose);
  if (params_.window <= 0.0) return;
  if (!history_.empty() && !(scan.stamp > history_.back().scan.stamp)) history_.clear();
  history_.push_back({scan, sensor_pose, std::cos(sensor_pose.theta), std::sin(sensor_pose.theta), scan.fullCircle()});
  // Keep what a query at the newest stamp can use (scans older than window before it are never consulted).
  while (history_.size() > params_.max_scans || history_.front().scan.stamp < scan.stamp - params_.window)
    history_.pop_front();
}

bool MotionEvidence::freeIn(const Past& past, const Eigen::Vector2d& p) const {
  const LaserScan& s = past.scan;
  const double dx = p.x() - past.pose.x, dy = p.y() - past.pose.y;
  const Eigen::Vector2d q(past.cos_theta * dx + past.sin_theta * dy, -past.sin_theta * dx + past.cos_theta * dy);
  const double r = q.norm();
  if (r < 1e-6) return false;
  const auto n = static_cast<long>(s.ranges.size());
  // Fractional beam index of the point's bearing, brought into one turn for a full-circle scan.
  double f = (std::atan2(q.y(), q.x()) - s.angle_min) / s.angle_increment;
  if (past.full_circle) {
    const double period = 2.0 * M_PI / std::abs(s.angle_increment);
    f = std::fmod(f, period);
    if (f < 0.0) f += period;
  }
  if (!(f >= 0.0)) return false;
  const long lo = static_cast<long>(std::floor(f));
  long hi = lo + 1;
  if (lo >= n) return false;
  if (hi >= n) {
    if (!past.full_circle) return false;
    hi = 0;
  }
  // Both bracketing beams end behind the point (or have no return within a range_max beyond it). A return stands
  // for its surface at its own bearing only: a surface whose range falls towards the point's bearing (seen from the
  // beam's other neighbour, less than memory_surface_gap away: one surface) is extrapolated there, `offset` beams
  // on, by slope_factor times that step (a wall seen at a grazing angle comes decimetres nearer within one beam).
  const double behind = r + params_.margin;
  for (const long k : {lo, hi}) {
    const auto b = static_cast<std::size_t>(k);
    if (s.valid(b)) {
      const double range = s.ranges[b];
      const long away = k == lo ? k - 1 : k + 1;  // the neighbour on the side away from the point
      const long a = past.full_circle ? (away + n) % n : away;
      double nearer = 0.0;
      if (a >= 0 && a < n && s.valid(static_cast<std::size_t>(a))) {
        const double step = static_cast<double>(s.ranges[static_cast<std::size_t>(a)]) - range;
        const double offset = k == lo ? f - static_cast<double>(lo) : static_cast<double>(lo + 1) - f;
        if (step > 0.0 && step < params_.memory_surface_gap) nearer = params_.slope_factor * step * offset;
      }
      if (range - nearer < behind) return false;
    } else if (!(s.range_max >= behind) || !s.beyondRange(b)) {
      return false;  // no return: free only if the laser would have seen something there (not a NaN or a too-close echo)
    }
  }
  return true;
}

bool MotionEvidence::seenFree(const Eigen::Vector2d& p, double stamp) const {
  std::size_t free = 0;
  for (const Past& past : history_) {
    const double age = stamp - past.scan.stamp;
    if (age < params_.min_age || age > params_.window) continue;
    if (freeIn(past, p) && ++free >= params_.min_free_scans) return true;
  }
  return false;
}

double MotionEvidence::freeFraction(const std::vector<Eigen::Vector2d>& points, double stamp,
                                    double stop_below) const {
  if (points.empty() || history_.empty()) return 0.0;
  const auto n = static_cast<double>(points.size());
  std::size_t free = 0, seen = 0;
  for (const Eigen::Vector2d& p : points) {
    if (seenFree(p, stamp)) ++free;
    ++seen;
    // Even if every remaining point were free the share would stay below stop_below.
    if (static_cast<double>(free) + (n - static_cast<double>(seen)) < stop_below * n) break;
  }
  return static_cast<double>(free) / n;
}

}  // namespace cairn::people_tracking
