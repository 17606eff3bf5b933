// Real-time correlative scan matching (Olson 2009) and branch-and-bound matching over max-pooled grids
// (Hess et al. 2016 §V-C, Algorithm 3).
#include "cairn/graph_slam/correlative_matcher.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace cairn::graph_slam {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Points rotated to every search angle and discretized to cells (with the initial translation applied).
struct DiscreteScans {
  int n_points = 0;
  int n_angles = 0;
  double step = 0;
  std::vector<double> angles;  ///< absolute headings
  std::vector<CellIndex> cells;  ///< n_angles * n_points
  std::vector<CellIndex> min, max;  ///< per angle: bounding box of the cells
  const CellIndex* scan(int k) const { return cells.data() + static_cast<std::size_t>(k) * static_cast<std::size_t>(n_points); }
};

double maxRange(const std::vector<Eigen::Vector2d>& pts, double cap) {
  double r = 0;
  for (const auto& p : pts) r = std::max(r, p.norm());
  return cap > 0.0 ? std::min(r, cap) : r;
}

DiscreteScans discretize(const std::vector<Eigen::Vector2d>& pts, const Pose2& initial, double angular,
                         double resolution, const Eigen::Vector2d& origin, double step_range, bool full_circle) {
  DiscreteScans d;
  d.n_points = static_cast<int>(pts.size());
  d.step = angularSearchStep(step_range, resolution);
  int k_lo, k_hi;
  if (full_circle) {
    const int n = static_cast<int>(std::ceil(kPi / d.step));
    d.step = kPi / n;
    k_lo = -n + 1;  // (-pi, pi]
    k_hi = n;
  } else {
    const int n = static_cast<int>(std::ceil(std::max(0.0, angular) / d.step));
    k_lo = -n;
    k_hi = n;
  }
  d.n_angles = k_hi - k_lo + 1;
  d.angles.resize(static_cast<std::size_t>(d.n_angles));
  d.cells.resize(static_cast<std::size_t>(d.n_angles) * pts.size());
  d.min.resize(static_cast<std::size_t>(d.n_angles));
  d.max.resize(static_cast<std::size_t>(d.n_angles));
  const double inv = 1.0 / resolution;
  for (int a = 0; a < d.n_angles; ++a) {
    const double th = initial.theta + (k_lo + a) * d.step;
    d.angles[static_cast<std::size_t>(a)] = th;
    const double c = std::cos(th), s = std::sin(th);
    CellIndex lo{std::numeric_limits<int>::max(), std::numeric_limits<int>::max()};
    CellIndex hi{std::numeric_limits<int>::min(), std::numeric_limits<int>::min()};
    CellIndex* out = d.cells.data() + static_cast<std::size_t>(a) * pts.size();
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double x = c * pts[i].x() - s * pts[i].y() + initial.t.x();
      const double y = s * pts[i].x() + c * pts[i].y() + initial.t.y();
      const CellIndex ci{static_cast<int>(std::floor((x - origin.x()) * inv)),
                         static_cast<int>(std::floor((y - origin.y()) * inv))};
      out[i] = ci;
      lo.x = std::min(lo.x, ci.x);
      lo.y = std::min(lo.y, ci.y);
      hi.x = std::max(hi.x, ci.x);
      hi.y = std::max(hi.y, ci.y);
    }
    d.min[static_cast<std::size_t>(a)] = lo;
    d.max[static_cast<std::size_t>(a)] = hi;
  }
  return d;
}

bool finitePoints(const std::vector<Eigen::Vector2d>& pts, const Pose2& initial) {
  if (!initial.t.allFinite() || !std::isfinite(initial.theta)) return false;
  return std::all_of(pts.begin(), pts.end(), [](const Eigen::Vector2d& p) { return p.allFinite(); });
}

}  // namespace

double angularSearchStep(double range, double resolution) {
  // Cartographer: the farthest point moves by at most one cell, with a small safety margin.
  constexpr double kSafety = 1.0 - 1e-3;
  if (!(range > resolution)) return kSafety * kPi / 4.0;
  return kSafety * std::acos(1.0 - resolution * resolution / (2.0 * range * range));
}

std::optional<MatchResult> correlativeMatch(const ProbabilityGrid& g, const std::vector<Eigen::Vector2d>& pts,
                                            const Pose2& initial, const SearchWindow& w, double min_score) {
  if (pts.empty() || g.width() == 0 || !finitePoints(pts, initial)) return std::nullopt;
  const double res = g.resolution();
  const DiscreteScans d = discretize(pts, initial, w.angular, res, g.origin(), maxRange(pts, w.max_step_range), false);
  const int n = static_cast<int>(std::ceil(std::max(0.0, w.linear) / res - 1e-9));
  const int side = 2 * n + 1;
  const int k_lo = -(d.n_angles - 1) / 2;
  std::vector<float> acc(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  const float pmin = static_cast<float>(g.options().min_probability);
  const double inv_n = 1.0 / static_cast<double>(pts.size());
  double best_rank = -1.0;
  MatchResult best;
  const bool penalize = w.translation_weight > 0.0 || w.rotation_weight > 0.0;
  std::vector<double> trans_pen(acc.size());
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx) {
      trans_pen[static_cast<std::size_t>(dy) * static_cast<std::size_t>(side) + static_cast<std::size_t>(dx)] =
          w.translation_weight * res * std::hypot(dx - n, dy - n);
    }
  }
  for (int a = 0; a < d.n_angles; ++a) {
    std::fill(acc.begin(), acc.end(), 0.0F);
    const CellIndex* cells = d.scan(a);
    for (int i = 0; i < d.n_points; ++i) {
      const int x0 = cells[i].x - n, y0 = cells[i].y - n;
      const bool inside_x = x0 >= 0 && x0 + side <= g.width();
      for (int dy = 0; dy < side; ++dy) {
        float* row = acc.data() + static_cast<std::size_t>(dy) * static_cast<std::size_t>(side);
        const int y = y0 + dy;
        if (y < 0 || y >= g.height()) {
          for (int dx = 0; dx < side; ++dx) row[dx] += pmin;
        } else if (inside_x) {
          for (int dx = 0; dx < side; ++dx) row[dx] += g.matchValueUnchecked(x0 + dx, y);
        } else {
          for (int dx = 0; dx < side; ++dx) row[dx] += g.matchValue(x0 + dx, y);
        }
      }
    }
    const double dth = (k_lo + a) * d.step;
    const double rot_pen = w.rotation_weight * std::abs(dth);
    for (int dy = 0; dy < side; ++dy) {
      for (int dx = 0; dx < side; ++dx) {
        const std::size_t idx = static_cast<std::size_t>(dy) * static_cast<std::size_t>(side) + static_cast<std::size_t>(dx);
        const double score = acc[idx] * inv_n;
        if (score <= best_rank) continue;  // the penalty factor is <= 1: cannot win
        double rank = score;
        if (penalize) {
          const double pen = trans_pen[idx] + rot_pen;
          rank = score * std::exp(-pen * pen);
          if (rank <= best_rank) continue;
        }
        best_rank = rank;
        best.score = score;
        best.pose.t = initial.t + res * Eigen::Vector2d(dx - n, dy - n);
        best.pose.theta = normalizeAngle(d.angles[static_cast<std::size_t>(a)]);
      }
    }
  }
  if (best_rank < 0.0 || best.score < min_score) return std::nullopt;
  return best;
}

BranchAndBoundMatcher::BranchAndBoundMatcher(const ProbabilityGrid& g, int depth)
    : resolution_(g.resolution()), origin_(g.origin()), width_(g.width()), height_(g.height()),
      min_value_(static_cast<float>(g.options().min_probability)), depth_(std::clamp(depth, 1, 16)) {
  level0_.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_));
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      level0_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)] =
          g.matchValueUnchecked(x, y);
    }
  }
  const auto quant = [](float v) { return static_cast<std::uint8_t>(std::min(255.0, std::ceil(static_cast<double>(v) * 255.0))); };
  const std::uint8_t qmin = quant(min_value_);
  // Level h stores max over [x, x + 2^h) x [y, y + 2^h) for x in [-(2^h - 1), width); built from level h-1
  // as the max of four shifted lookups.
  levels_.resize(static_cast<std::size_t>(depth_ - 1));
  for (int h = 1; h < depth_; ++h) {
    Level& L = levels_[static_cast<std::size_t>(h - 1)];
    const int half = 1 << (h - 1);
    L.pad = (1 << h) - 1;
    L.w = width_ + L.pad;
    L.h = height_ + L.pad;
    L.v.resize(static_cast<std::size_t>(L.w) * static_cast<std::size_t>(L.h));
    auto prev = [&](int x, int y) -> std::uint8_t {
      if (h == 1) {
        if (x < 0 || y < 0 || x >= width_ || y >= height_) return qmin;
        return quant(level0_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)]);
      }
      const Level& P = levels_[static_cast<std::size_t>(h - 2)];
      if (x < -P.pad || y < -P.pad || x >= width_ || y >= height_) return qmin;
      return P.v[static_cast<std::size_t>(y + P.pad) * static_cast<std::size_t>(P.w) + static_cast<std::size_t>(x + P.pad)];
    };
    for (int y = -L.pad; y < height_; ++y) {
      for (int x = -L.pad; x < width_; ++x) {
        L.v[static_cast<std::size_t>(y + L.pad) * static_cast<std::size_t>(L.w) + static_cast<std::size_t>(x + L.pad)] =
            std::max(std::max(prev(x, y), prev(x + half, y)), std::max(prev(x, y + half), prev(x + half, y + half)));
      }
    }
  }
}

std::optional<MatchResult> BranchAndBoundMatcher::match(const std::vector<Eigen::Vector2d>& pts, const Pose2& initial,
                                                        const SearchWindow& w, double min_score) const {
  return search(pts, initial, w.linear, w.angular, false, min_score, w.max_step_range);
}

std::optional<MatchResult> BranchAndBoundMatcher::matchFull(const std::vector<Eigen::Vector2d>& pts,
                                                            double min_score) const {
  Pose2 initial;
  initial.t = origin_;
  const double linear = (width_ + height_ + 2) * resolution_;
  return search(pts, initial, linear, kPi, true, min_score, 0.0);
}

std::optional<MatchResult> BranchAndBoundMatcher::search(const std::vector<Eigen::Vector2d>& pts, const Pose2& initial,
                                                         double linear, double angular, bool full, double min_score,
                                                         double max_step_range) const {
  scored_ = 0;
  if (pts.empty() || width_ == 0 || !finitePoints(pts, initial)) return std::nullopt;
  const DiscreteScans d = discretize(pts, initial, angular, resolution_, origin_, maxRange(pts, max_step_range), full);
  const int n = static_cast<int>(std::ceil(std::max(0.0, linear) / resolution_ - 1e-9));
  const int N = d.n_points;
  const double inv_n = 1.0 / N;
  const double inv_qn = 1.0 / (255.0 * N);

  struct Candidate {
    int a, ox, oy;
    double score;
  };
  // Offset bounds per angle (inclusive); with `full` shrunk so that the scan's cell box overlaps the grid.
  std::vector<std::array<int, 4>> bounds(static_cast<std::size_t>(d.n_angles));
  for (int a = 0; a < d.n_angles; ++a) {
    std::array<int, 4> b{-n, n, -n, n};
    if (full) {
      const CellIndex lo = d.min[static_cast<std::size_t>(a)], hi = d.max[static_cast<std::size_t>(a)];
      b = {std::max(-n, -hi.x), std::min(n, width_ - 1 - lo.x), std::max(-n, -hi.y), std::min(n, height_ - 1 - lo.y)};
    }
    bounds[static_cast<std::size_t>(a)] = b;
  }
  auto scoreAt = [&](const Candidate& c, int h) -> double {
    ++scored_;
    const CellIndex* cells = d.scan(c.a);
    if (h == 0) {
      float s = 0.0F;
      for (int i = 0; i < N; ++i) {
        const int x = cells[i].x + c.ox, y = cells[i].y + c.oy;
        s += (x < 0 || y < 0 || x >= width_ || y >= height_)
                 ? min_value_
                 : level0_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
      }
      return s * inv_n;
    }
    const Level& L = levels_[static_cast<std::size_t>(h - 1)];
    const unsigned qmin = static_cast<unsigned>(std::min(255.0, std::ceil(static_cast<double>(min_value_) * 255.0)));
    unsigned s = 0;
    for (int i = 0; i < N; ++i) {
      const int x = cells[i].x + c.ox + L.pad, y = cells[i].y + c.oy + L.pad;
      s += (x < 0 || y < 0 || x >= L.w || y >= L.h)
               ? qmin
               : L.v[static_cast<std::size_t>(y) * static_cast<std::size_t>(L.w) + static_cast<std::size_t>(x)];
    }
    return s * inv_qn;
  };
  const int top = depth_ - 1;
  const int top_step = 1 << top;
  std::vector<Candidate> roots;
  for (int a = 0; a < d.n_angles; ++a) {
    const auto& b = bounds[static_cast<std::size_t>(a)];
    for (int ox = b[0]; ox <= b[1]; ox += top_step) {
      for (int oy = b[2]; oy <= b[3]; oy += top_step) {
        Candidate c{a, ox, oy, 0.0};
        c.score = scoreAt(c, top);
        roots.push_back(c);
      }
    }
  }
  auto byScore = [](const Candidate& l, const Candidate& r) { return l.score > r.score; };
  std::sort(roots.begin(), roots.end(), byScore);

  // Depth-first branch and bound; best_score starts at min_score so weaker leaves are never accepted.
  double best_score = min_score;
  std::optional<Candidate> best;
  constexpr double kEps = 1e-9;  // bounds are exact upper bounds up to rounding
  auto recurse = [&](auto&& self, std::vector<Candidate>& cands, int h) -> void {
    for (const Candidate& c : cands) {
      if (best ? c.score + kEps <= best_score : c.score + kEps < best_score) return;
      if (h == 0) {
        if (c.score >= min_score && (!best || c.score > best_score)) {
          best = c;
          best_score = c.score;
        }
        return;  // sorted: the rest are not better
      }
      const int half = 1 << (h - 1);
      const auto& b = bounds[static_cast<std::size_t>(c.a)];
      std::vector<Candidate> children;
      children.reserve(4);
      for (int ix = 0; ix < 2; ++ix) {
        const int ox = c.ox + ix * half;
        if (ox > b[1]) continue;
        for (int iy = 0; iy < 2; ++iy) {
          const int oy = c.oy + iy * half;
          if (oy > b[3]) continue;
          Candidate ch{c.a, ox, oy, 0.0};
          ch.score = scoreAt(ch, h - 1);
          children.push_back(ch);
        }
      }
      std::sort(children.begin(), children.end(), byScore);
      self(self, children, h - 1);
    }
  };
  recurse(recurse, roots, top);
  if (!best) return std::nullopt;
  MatchResult r;
  r.score = best->score;
  r.pose.t = initial.t + resolution_ * Eigen::Vector2d(best->ox, best->oy);
  r.pose.theta = normalizeAngle(d.angles[static_cast<std::size_t>(best->a)]);
  return r;
}

}  // namespace cairn::graph_slam
