// Probability grid: odds updates, ray casting, growth, bicubic interpolation (Hess et al. 2016 §IV-B/C).
#include "cairn/graph_slam/probability_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cairn::graph_slam {
namespace {

double odds(double p) { return p / (1.0 - p); }

// Catmull-Rom cubic convolution (Keys 1981, a = -0.5) of samples at -1, 0, 1, 2 evaluated at t in [0, 1].
inline double cubic(double p0, double p1, double p2, double p3, double t) {
  return 0.5 * (2.0 * p1 + t * ((p2 - p0) + t * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + t * (3.0 * (p1 - p2) + p3 - p0))));
}
inline double cubicDerivative(double p0, double p1, double p2, double p3, double t) {
  return 0.5 * ((p2 - p0) + t * (2.0 * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + t * 3.0 * (3.0 * (p1 - p2) + p3 - p0)));
}

constexpr int kGrowMargin = 32;  // cells added beyond what an insertion needs (amortizes growth)

}  // namespace

ProbabilityGrid::ProbabilityGrid(double resolution, ProbabilityGridOptions options)
    : resolution_(resolution), options_(options) {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("ProbabilityGrid: resolution must be positive and finite");
  }
  if (!(options.min_probability > 0.0 && options.min_probability < options.max_probability &&
        options.max_probability < 1.0 && options.hit_probability > 0.0 && options.hit_probability < 1.0 &&
        options.miss_probability > 0.0 && options.miss_probability < 1.0)) {
    throw std::invalid_argument(
        "ProbabilityGrid: need 0 < min_probability < max_probability < 1 and hit/miss probabilities in (0, 1)");
  }
  min_value_ = static_cast<float>(options_.min_probability);
  odds_hit_ = odds(options_.hit_probability);
  odds_miss_ = odds(options_.miss_probability);
}

CellIndex ProbabilityGrid::cellIndex(const Eigen::Vector2d& p) const {
  return {static_cast<int>(std::floor((p.x() - origin_.x()) / resolution_)),
          static_cast<int>(std::floor((p.y() - origin_.y()) / resolution_))};
}

Eigen::Vector2d ProbabilityGrid::cellCenter(int x, int y) const {
  return origin_ + resolution_ * Eigen::Vector2d(x + 0.5, y + 0.5);
}

bool ProbabilityGrid::known(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return false;
  return cells_[flat(x, y)] > 0.0F;
}

double ProbabilityGrid::probability(int x, int y) const {
  if (!known(x, y)) return kUnknownProbability;
  return cells_[flat(x, y)];
}

bool ProbabilityGrid::known(const Eigen::Vector2d& p) const {
  const CellIndex c = cellIndex(p);
  return known(c.x, c.y);
}

double ProbabilityGrid::probability(const Eigen::Vector2d& p) const {
  const CellIndex c = cellIndex(p);
  return probability(c.x, c.y);
}

void ProbabilityGrid::growToInclude(const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  if (width_ == 0) {
    origin_ = Eigen::Vector2d((std::floor(min.x() / resolution_) - kGrowMargin) * resolution_,
                              (std::floor(min.y() / resolution_) - kGrowMargin) * resolution_);
    width_ = static_cast<int>(std::floor((max.x() - origin_.x()) / resolution_)) + 1 + kGrowMargin;
    height_ = static_cast<int>(std::floor((max.y() - origin_.y()) / resolution_)) + 1 + kGrowMargin;
    cells_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0.0F);
    marks_.assign(cells_.size(), 0);
    epoch_ = 0;
    return;
  }
  const CellIndex lo = cellIndex(min);
  const CellIndex hi = cellIndex(max);
  if (lo.x >= 0 && lo.y >= 0 && hi.x < width_ && hi.y < height_) return;
  // Grow every side that overflows by what it needs plus max(margin, half the current size).
  const int add_left = lo.x < 0 ? -lo.x + std::max(kGrowMargin, width_ / 2) : 0;
  const int add_bottom = lo.y < 0 ? -lo.y + std::max(kGrowMargin, height_ / 2) : 0;
  const int add_right = hi.x >= width_ ? hi.x - width_ + 1 + std::max(kGrowMargin, width_ / 2) : 0;
  const int add_top = hi.y >= height_ ? hi.y - height_ + 1 + std::max(kGrowMargin, height_ / 2) : 0;
  const int nw = width_ + add_left + add_right;
  const int nh = height_ + add_bottom + add_top;
  std::vector<float> cells(static_cast<std::size_t>(nw) * static_cast<std::size_t>(nh), 0.0F);
  for (int y = 0; y < height_; ++y) {
    std::copy_n(cells_.begin() + static_cast<std::ptrdiff_t>(flat(0, y)), width_,
                cells.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y + add_bottom) * static_cast<std::size_t>(nw) +
                                                            static_cast<std::size_t>(add_left)));
  }
  cells_ = std::move(cells);
  width_ = nw;
  height_ = nh;
  origin_ -= resolution_ * Eigen::Vector2d(add_left, add_bottom);
  marks_.assign(cells_.size(), 0);
  epoch_ = 0;
}

void ProbabilityGrid::insert(const RangeData& data, const Pose2& pose) {
  const Eigen::Matrix2d R = rotation2(pose.theta);
  const Eigen::Vector2d o = R * data.origin + pose.t;
  Eigen::Vector2d lo = o, hi = o;
  for (const auto& p : data.returns) {
    const Eigen::Vector2d q = R * p + pose.t;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  if (options_.insert_free_space) {
    for (const auto& p : data.misses) {
      const Eigen::Vector2d q = R * p + pose.t;
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  }
  if (!lo.allFinite() || !hi.allFinite()) return;
  growToInclude(lo, hi);
  if (marks_.size() != cells_.size()) marks_.assign(cells_.size(), 0);
  if (++epoch_ == 0) {  // wrapped: clear the marks
    std::fill(marks_.begin(), marks_.end(), std::uint8_t{0});
    epoch_ = 1;
  }
  const auto pmin = static_cast<float>(options_.min_probability);
  const auto pmax = static_cast<float>(options_.max_probability);
  auto update = [&](std::size_t i, double k) {
    if (marks_[i] == epoch_) return;
    marks_[i] = epoch_;
    const double p = cells_[i] > 0.0F ? cells_[i] : 0.5;  // unknown: prior 0.5 (first hit -> p_hit)
    const double od = p / (1.0 - p) * k;
    cells_[i] = std::clamp(static_cast<float>(od / (1.0 + od)), pmin, pmax);
  };
  // Hits first so a cell hit by this scan is not also cleared by another of its rays.
  for (const auto& p : data.returns) {
    const CellIndex c = cellIndex(R * p + pose.t);
    update(flat(c.x, c.y), odds_hit_);
  }
  if (!options_.insert_free_space) return;
  // Amanatides & Woo traversal in cell units from the sensor to each end; the end cell of a return is
  // excluded (it was hit), the end cell of a miss is included.
  const Eigen::Vector2d u0 = (o - origin_) / resolution_;
  const CellIndex c0{static_cast<int>(std::floor(u0.x())), static_cast<int>(std::floor(u0.y()))};
  auto cast = [&](const Eigen::Vector2d& end, bool include_end) {
    const Eigen::Vector2d u1 = (end - origin_) / resolution_;
    const CellIndex c1{static_cast<int>(std::floor(u1.x())), static_cast<int>(std::floor(u1.y()))};
    const Eigen::Vector2d d = u1 - u0;
    const int sx = d.x() > 0 ? 1 : -1, sy = d.y() > 0 ? 1 : -1;
    const double inf = std::numeric_limits<double>::infinity();
    const double tdx = d.x() != 0.0 ? std::abs(1.0 / d.x()) : inf;
    const double tdy = d.y() != 0.0 ? std::abs(1.0 / d.y()) : inf;
    double tx = d.x() != 0.0 ? ((sx > 0 ? (c0.x + 1 - u0.x()) : (u0.x() - c0.x)) * tdx) : inf;
    double ty = d.y() != 0.0 ? ((sy > 0 ? (c0.y + 1 - u0.y()) : (u0.y() - c0.y)) * tdy) : inf;
    int x = c0.x, y = c0.y;
    const int steps = std::abs(c1.x - c0.x) + std::abs(c1.y - c0.y);
    for (int s = 0; s < steps; ++s) {
      update(flat(x, y), odds_miss_);
      if (tx < ty) {
        x += sx;
        tx += tdx;
      } else {
        y += sy;
        ty += tdy;
      }
    }
    if (include_end && x == c1.x && y == c1.y) update(flat(x, y), odds_miss_);
  };
  for (const auto& p : data.returns) cast(R * p + pose.t, false);
  for (const auto& p : data.misses) cast(R * p + pose.t, true);
}

double ProbabilityGrid::interpolate(const Eigen::Vector2d& p, Eigen::Vector2d* grad) const {
  const double ux = (p.x() - origin_.x()) / resolution_ - 0.5;
  const double uy = (p.y() - origin_.y()) / resolution_ - 0.5;
  if (!std::isfinite(ux) || !std::isfinite(uy)) {
    if (grad) grad->setZero();
    return options_.min_probability;
  }
  const double fx0 = std::floor(ux), fy0 = std::floor(uy);
  const double tx = ux - fx0, ty = uy - fy0;
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  double rows[4], drows[4];
  const bool inside = x0 >= 1 && y0 >= 1 && x0 + 2 < width_ && y0 + 2 < height_;
  for (int j = 0; j < 4; ++j) {
    double v[4];
    for (int i = 0; i < 4; ++i) {
      v[i] = inside ? matchValueUnchecked(x0 - 1 + i, y0 - 1 + j) : matchValue(x0 - 1 + i, y0 - 1 + j);
    }
    rows[j] = cubic(v[0], v[1], v[2], v[3], tx);
    drows[j] = cubicDerivative(v[0], v[1], v[2], v[3], tx);
  }
  if (grad) {
    *grad = Eigen::Vector2d(cubic(drows[0], drows[1], drows[2], drows[3], ty),
                            cubicDerivative(rows[0], rows[1], rows[2], rows[3], ty)) /
            resolution_;
  }
  return cubic(rows[0], rows[1], rows[2], rows[3], ty);
}

bool ProbabilityGrid::knownBounds(CellIndex& min, CellIndex& max) const {
  bool any = false;
  min = {width_, height_};
  max = {-1, -1};
  for (int y = 0; y < height_; ++y) {
    const float* row = cells_.data() + flat(0, y);
    for (int x = 0; x < width_; ++x) {
      if (row[x] > 0.0F) {
        any = true;
        min.x = std::min(min.x, x);
        max.x = std::max(max.x, x);
        min.y = std::min(min.y, y);
        max.y = std::max(max.y, y);
      }
    }
  }
  return any;
}

std::size_t ProbabilityGrid::knownCells() const {
  return static_cast<std::size_t>(std::count_if(cells_.begin(), cells_.end(), [](float v) { return v > 0.0F; }));
}

void ProbabilityGrid::crop() {
  marks_.clear();
  marks_.shrink_to_fit();
  epoch_ = 0;
  CellIndex lo, hi;
  if (!knownBounds(lo, hi)) return;
  const int nw = hi.x - lo.x + 1, nh = hi.y - lo.y + 1;
  if (nw == width_ && nh == height_) return;
  std::vector<float> cells(static_cast<std::size_t>(nw) * static_cast<std::size_t>(nh));
  for (int y = 0; y < nh; ++y) {
    std::copy_n(cells_.begin() + static_cast<std::ptrdiff_t>(flat(lo.x, lo.y + y)), nw,
                cells.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * static_cast<std::size_t>(nw)));
  }
  cells_ = std::move(cells);
  origin_ += resolution_ * Eigen::Vector2d(lo.x, lo.y);
  width_ = nw;
  height_ = nh;
}

}  // namespace cairn::graph_slam
