// Global scan descriptor (Stüde 2024 §3.2.1, eq. 3.7; features after Granström et al., ICRA 2009).
//
// The thesis fixes the structure (32 scalar features χᴵ, 9 range histograms χᴵᴵ, |Δ| and Pearson correlation as
// pair features) but not the 2D feature list; the 32 below are our choice, all functions of ranges and relative
// angles only, so they are invariant to rotating the scan (and, for 360° scans, to a cyclic shift of the beams).
#include "cairn/graph_slam/scan_descriptor.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace cairn::graph_slam {

namespace {

constexpr double kCurvatureCap = 10.0;      // 1/m: curvature of triples is clipped here (range noise)
constexpr double kStraightCurvature = 0.5;  // 1/m: triples below count as "straight"

struct Point {
  double x, y, r;
  bool clamped;  // no return or beyond r_max: moved to r_max (Stüde §3.2.1)
};

void checkOptions(const DescriptorOptions& o) {
  if (!(o.max_range > 0.0) || !std::isfinite(o.max_range)) throw std::invalid_argument("DescriptorOptions.max_range must be > 0");
  if (!(o.min_range >= 0.0) || !(o.min_range < o.max_range))
    throw std::invalid_argument("DescriptorOptions.min_range must be in [0, max_range)");
  if (!(o.angular_resolution > 0.0) || !std::isfinite(o.angular_resolution))
    throw std::invalid_argument("DescriptorOptions.angular_resolution must be > 0");
  for (double b : o.histogram_bin_sizes)
    if (!(b > 0.0) || !std::isfinite(b)) throw std::invalid_argument("DescriptorOptions.histogram_bin_sizes must be > 0");
  for (double g : o.gap_distances)
    if (!(g > 0.0) || !std::isfinite(g)) throw std::invalid_argument("DescriptorOptions.gap_distances must be > 0");
}

// Resamples the beams to bins of at least `angular_resolution`, keeping the closest reading of each bin (a
// coarser scanner sees the nearest obstacle of its sector); +inf counts only if a bin has no finite reading.
std::vector<Point> resample(const sim::LaserScan& scan, const DescriptorOptions& o, double& fov) {
  const double inc = scan.angle_increment;
  if (!(inc > 0.0) || !std::isfinite(inc)) throw std::invalid_argument("LaserScan.angle_increment must be > 0 and finite");
  if (scan.ranges.empty()) throw std::invalid_argument("LaserScan.ranges is empty");
  if (!std::isfinite(scan.angle_min)) throw std::invalid_argument("LaserScan.angle_min is not finite");
  const std::size_t n = scan.ranges.size();
  fov = static_cast<double>(n) * inc;
  const double step = std::max(inc, o.angular_resolution);
  const auto bins = static_cast<std::size_t>(std::max(1L, std::lround(fov / step)));
  const double width = fov / static_cast<double>(bins);

  std::vector<double> best(bins, std::numeric_limits<double>::quiet_NaN());
  std::vector<std::size_t> beam(bins, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = scan.ranges[i];
    if (std::isnan(r) || r <= o.min_range) continue;  // invalid beam (NaN, zero, negative, too close)
    const auto j = std::min(bins - 1, static_cast<std::size_t>((static_cast<double>(i) + 0.5) * inc / width));
    if (std::isnan(best[j]) || r < best[j]) {
      best[j] = r;
      beam[j] = i;
    }
  }
  std::vector<Point> pts;
  pts.reserve(bins);
  for (std::size_t j = 0; j < bins; ++j) {
    if (std::isnan(best[j])) continue;
    const bool clamped = !(best[j] < o.max_range);
    const double r = clamped ? o.max_range : best[j];
    const double a = static_cast<double>(beam[j]) * inc;  // relative to angle_min: rotation-invariant features
    pts.push_back({r * std::cos(a), r * std::sin(a), r, clamped});
  }
  return pts;
}

double quantileSorted(const std::vector<double>& s, double q) {
  if (s.empty()) return 0.0;
  const double pos = q * static_cast<double>(s.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, s.size() - 1);
  return s[lo] + (pos - static_cast<double>(lo)) * (s[hi] - s[lo]);
}

struct Moments {
  double mean = 0.0, sd = 0.0;
};
Moments moments(const std::vector<double>& v) {
  Moments m;
  if (v.empty()) return m;
  for (double x : v) m.mean += x;
  m.mean /= static_cast<double>(v.size());
  double var = 0.0;
  for (double x : v) var += (x - m.mean) * (x - m.mean);
  m.sd = std::sqrt(var / static_cast<double>(v.size()));
  return m;
}

double dist(const Point& a, const Point& b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

const std::vector<std::string>& scalarFeatureNames() {
  static const std::vector<std::string> names{
      "range_mean", "range_std", "range_median", "range_p10", "range_p90", "range_iqr", "range_skewness",
      "range_kurtosis", "max_range_fraction", "range_entropy", "range_diff_mean", "range_diff_std", "step_mean",
      "step_std", "gaps_g1", "gaps_g2", "gaps_g3", "segment_length_mean", "area", "wall_length", "compactness",
      "centroid_distance", "area_centroid_distance", "spread_major", "spread_minor", "eccentricity",
      "mean_distance_to_centroid", "curvature_mean", "curvature_std", "straight_fraction", "orientation_r2",
      "orientation_r4"};
  return names;
}

ScanDescriptor computeDescriptor(const sim::LaserScan& scan, const DescriptorOptions& o) {
  checkOptions(o);
  ScanDescriptor d;
  const std::vector<Point> p = resample(scan, o, d.fov);
  d.points = static_cast<int>(p.size());
  d.scalars.assign(kScalarFeatureCount, 0.0);
  d.histograms.resize(kHistogramCount);
  for (std::size_t h = 0; h < kHistogramCount; ++h) {
    const double b = o.histogram_bin_sizes[h];
    d.histograms[h].assign(static_cast<std::size_t>(std::ceil(o.max_range / b - 1e-9)), 0.0);
  }
  if (p.empty()) return d;
  const std::size_t n = p.size();
  const double nn = static_cast<double>(n);
  // A 360° scan is a closed polygon: its consecutive pairs wrap around, so a cyclic shift changes nothing.
  const bool cyclic = d.fov >= 2.0 * std::numbers::pi - 1.5 * static_cast<double>(scan.angle_increment);
  const std::size_t pairs = cyclic ? n : n - 1;
  auto next = [n](std::size_t k) { return (k + 1) % n; };
  std::vector<double>& f = d.scalars;

  // Range histograms χᴵᴵ (Stüde Fig. 3.4: annuli of width b_j), normalized to fractions of the points.
  for (std::size_t h = 0; h < kHistogramCount; ++h) {
    std::vector<double>& hist = d.histograms[h];
    for (const Point& q : p) {
      const auto k = std::min(hist.size() - 1, static_cast<std::size_t>(q.r / o.histogram_bin_sizes[h]));
      hist[k] += 1.0 / nn;
    }
  }

  // Range statistics.
  std::vector<double> r(n);
  std::size_t clamped = 0;
  for (std::size_t k = 0; k < n; ++k) {
    r[k] = p[k].r;
    clamped += p[k].clamped ? 1 : 0;
  }
  const Moments rm = moments(r);
  std::vector<double> rs = r;
  std::sort(rs.begin(), rs.end());
  f[0] = rm.mean;
  f[1] = rm.sd;
  f[2] = quantileSorted(rs, 0.5);
  f[3] = quantileSorted(rs, 0.1);
  f[4] = quantileSorted(rs, 0.9);
  f[5] = quantileSorted(rs, 0.75) - quantileSorted(rs, 0.25);
  if (rm.sd > 1e-9) {
    double m3 = 0.0, m4 = 0.0;
    for (double x : r) {
      const double z = (x - rm.mean) / rm.sd;
      m3 += z * z * z;
      m4 += z * z * z * z;
    }
    f[6] = m3 / nn;
    f[7] = m4 / nn - 3.0;
  }
  f[8] = static_cast<double>(clamped) / nn;
  {
    const std::vector<double>& h1 = d.histograms[4];  // 1 m annuli
    double e = 0.0;
    for (double q : h1)
      if (q > 0.0) e -= q * std::log(q);
    f[9] = e;
  }

  // Consecutive points: range differences, steps, gaps (Granström et al. 2009), segments.
  std::vector<double> dr, step;
  dr.reserve(pairs);
  step.reserve(pairs);
  for (std::size_t k = 0; k < pairs; ++k) {
    dr.push_back(std::abs(p[next(k)].r - p[k].r));
    step.push_back(dist(p[k], p[next(k)]));
  }
  const Moments drm = moments(dr), sm = moments(step);
  f[10] = drm.mean;
  f[11] = drm.sd;
  f[12] = sm.mean;
  f[13] = sm.sd;
  for (std::size_t g = 0; g < 3; ++g)
    f[14 + g] = static_cast<double>(std::count_if(step.begin(), step.end(),
                                                  [&](double s) { return s > o.gap_distances[g]; }));
  // Wall edges: consecutive points closer than the first gap distance, neither clamped to r_max.
  std::vector<char> wall(pairs, 0);
  for (std::size_t k = 0; k < pairs; ++k)
    wall[k] = step[k] <= o.gap_distances[0] && !p[k].clamped && !p[next(k)].clamped ? 1 : 0;
  {
    // Segments: maximal runs of wall edges; a segment's length is the sum of its steps. A 360° scan starts the
    // walk after a break, so the segment across the seam is not split (cyclic-shift invariance).
    std::size_t start = 0;
    if (cyclic) {
      const auto br = std::find(wall.begin(), wall.end(), 0);
      start = br == wall.end() ? 0 : static_cast<std::size_t>(br - wall.begin()) + 1;
    }
    std::vector<double> lengths;
    double cur = 0.0;
    bool open = false;
    for (std::size_t m = 0; m < pairs; ++m) {
      const std::size_t k = (start + m) % pairs;
      if (wall[k]) {
        cur += step[k];
        open = true;
      } else if (open) {
        lengths.push_back(cur);
        cur = 0.0;
        open = false;
      }
    }
    if (open) lengths.push_back(cur);
    double total = 0.0;
    for (double l : lengths) total += l;
    f[17] = lengths.empty() ? 0.0 : total / static_cast<double>(lengths.size());
    f[19] = total;
  }

  // Polygon (the sensor origin closes it unless the scan covers 360°): area, perimeter, area centroid.
  {
    double a2 = 0.0, cx = 0.0, cy = 0.0, perim = 0.0;
    auto edge = [&](double x0, double y0, double x1, double y1) {
      const double c = x0 * y1 - x1 * y0;
      a2 += c;
      cx += (x0 + x1) * c;
      cy += (y0 + y1) * c;
      perim += std::hypot(x1 - x0, y1 - y0);
    };
    for (std::size_t k = 0; k < pairs; ++k) edge(p[k].x, p[k].y, p[next(k)].x, p[next(k)].y);
    if (!cyclic) {
      edge(p[n - 1].x, p[n - 1].y, 0.0, 0.0);
      edge(0.0, 0.0, p[0].x, p[0].y);
    }
    const double area = 0.5 * std::abs(a2);
    f[18] = area;
    f[20] = perim > 0.0 ? 4.0 * std::numbers::pi * area / (perim * perim) : 0.0;
    f[22] = std::abs(a2) > 1e-12 ? std::hypot(cx, cy) / (3.0 * std::abs(a2)) : 0.0;
  }

  // Point-set moments.
  {
    double mx = 0.0, my = 0.0;
    for (const Point& q : p) {
      mx += q.x;
      my += q.y;
    }
    mx /= nn;
    my /= nn;
    double sxx = 0.0, syy = 0.0, sxy = 0.0, md = 0.0;
    for (const Point& q : p) {
      sxx += (q.x - mx) * (q.x - mx);
      syy += (q.y - my) * (q.y - my);
      sxy += (q.x - mx) * (q.y - my);
      md += std::hypot(q.x - mx, q.y - my);
    }
    sxx /= nn;
    syy /= nn;
    sxy /= nn;
    const double tr = 0.5 * (sxx + syy), det = std::sqrt(std::max(0.0, 0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy));
    const double l1 = tr + det, l2 = std::max(0.0, tr - det);
    f[21] = std::hypot(mx, my);
    f[23] = std::sqrt(l1);
    f[24] = std::sqrt(l2);
    f[25] = l1 > 1e-12 ? std::sqrt(l2 / l1) : 0.0;
    f[26] = md / nn;
  }

  // Local geometry on wall points (no gap, not clamped): Menger curvature of triples, edge orientations.
  {
    std::vector<double> curv;
    std::size_t straight = 0;
    const std::size_t triples = cyclic ? n : (n >= 2 ? n - 2 : 0);
    for (std::size_t k = 0; k < triples && n >= 3; ++k) {
      const std::size_t k1 = next(k), k2 = next(k1);
      if (!wall[k] || !wall[k1]) continue;
      const double a = step[k], b = step[k1], c = dist(p[k], p[k2]);
      if (a * b * c < 1e-12) continue;
      const double cr = std::abs((p[k1].x - p[k].x) * (p[k2].y - p[k].y) - (p[k1].y - p[k].y) * (p[k2].x - p[k].x));
      const double kappa = std::min(kCurvatureCap, 2.0 * cr / (a * b * c));  // 4·area/(abc), area = cr/2
      curv.push_back(kappa);
      straight += kappa < kStraightCurvature ? 1 : 0;
    }
    const Moments cm = moments(curv);
    f[27] = cm.mean;
    f[28] = cm.sd;
    f[29] = curv.empty() ? 0.0 : static_cast<double>(straight) / static_cast<double>(curv.size());
    // Mean resultant length of doubled / quadrupled edge angles, length-weighted: 1 for parallel walls (r2) and
    // for rectilinear (Manhattan) layouts (r4); rotating the scan multiplies the sums by a unit phasor only.
    std::complex<double> z2{0.0, 0.0}, z4{0.0, 0.0};
    double wsum = 0.0;
    for (std::size_t k = 0; k < pairs; ++k) {
      if (!wall[k]) continue;
      const double ang = std::atan2(p[next(k)].y - p[k].y, p[next(k)].x - p[k].x);
      z2 += step[k] * std::polar(1.0, 2.0 * ang);
      z4 += step[k] * std::polar(1.0, 4.0 * ang);
      wsum += step[k];
    }
    if (wsum > 0.0) {
      f[30] = std::abs(z2) / wsum;
      f[31] = std::abs(z4) / wsum;
    }
  }
  return d;
}

double pearsonCorrelation(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) throw std::invalid_argument("pearsonCorrelation: sequences differ in length");
  if (a.empty()) return 0.0;
  const Moments ma = moments(a), mb = moments(b);
  if (ma.sd <= 1e-15 || mb.sd <= 1e-15) return 0.0;
  double s = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) s += (a[k] - ma.mean) * (b[k] - mb.mean);
  return std::clamp(s / (static_cast<double>(a.size()) * (ma.sd * mb.sd)), -1.0, 1.0);  // symmetric in a, b
}

std::vector<double> pairFeatures(const ScanDescriptor& a, const ScanDescriptor& b) {
  if (a.scalars.size() != kScalarFeatureCount || b.scalars.size() != kScalarFeatureCount ||
      a.histograms.size() != kHistogramCount || b.histograms.size() != kHistogramCount)
    throw std::invalid_argument("pairFeatures: descriptor without 32 scalars and 9 histograms");
  std::vector<double> out;
  out.reserve(kPairFeatureCount);
  // Stüde §3.2.1: element-wise |χᴵ_i − χᴵ_j| ...
  for (std::size_t k = 0; k < kScalarFeatureCount; ++k) out.push_back(std::abs(a.scalars[k] - b.scalars[k]));
  // ... and Pearson's correlation of the range histograms χᴵᴵ.
  for (std::size_t h = 0; h < kHistogramCount; ++h) {
    if (a.histograms[h].size() != b.histograms[h].size())
      throw std::invalid_argument("pairFeatures: histograms of different sizes (descriptors from different options)");
    out.push_back(pearsonCorrelation(a.histograms[h], b.histograms[h]));
  }
  return out;
}

}  // namespace cairn::graph_slam
