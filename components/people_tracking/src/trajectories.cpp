#include "cairn/people_tracking/trajectories.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "cairn/people_tracking/scan.hpp"

namespace cairn::people_tracking {

std::optional<Eigen::Vector2d> TrajectorySet::positionAt(int id, double t) const {
  const auto it = people.find(id);
  if (it == people.end()) return std::nullopt;
  const auto& v = it->second;
  if (v.empty() || t < v.front().t || t > v.back().t) return std::nullopt;
  const auto hi = std::lower_bound(v.begin(), v.end(), t, [](const TrajectoryPoint& a, double x) { return a.t < x; });
  if (hi->t == t) return hi->p;
  const auto lo = hi - 1;
  if (hi->t - lo->t > max_gap) return std::nullopt;
  const double a = (t - lo->t) / (hi->t - lo->t);
  return Eigen::Vector2d((1 - a) * lo->p + a * hi->p);
}

void smoothTrajectories(TrajectorySet& set, double sigma) {
  if (!(sigma > 0.0) || !std::isfinite(sigma))
    throw InputError("trajectory smoothing sigma must be a positive number of seconds, got " + std::to_string(sigma));
  for (auto& [id, v] : set.people) {
    std::vector<TrajectoryPoint> out = v;
    for (std::size_t i = 0; i < v.size(); ++i) {
      std::size_t a = i, b = i;  // the window: contiguous annotations within 3 sigma of point i
      while (a > 0 && v[a].t - v[a - 1].t <= set.max_gap && v[i].t - v[a - 1].t <= 3.0 * sigma) --a;
      while (b + 1 < v.size() && v[b + 1].t - v[b].t <= set.max_gap && v[b + 1].t - v[i].t <= 3.0 * sigma) ++b;
      // Weighted least squares p(t) = c0 + c1 (t - t_i); the estimate at t_i is c0.
      double s0 = 0.0, s1 = 0.0, s2 = 0.0;
      Eigen::Vector2d m0 = Eigen::Vector2d::Zero(), m1 = Eigen::Vector2d::Zero();
      for (std::size_t j = a; j <= b; ++j) {
        const double d = v[j].t - v[i].t, w = std::exp(-0.5 * d * d / (sigma * sigma));
        s0 += w;
        s1 += w * d;
        s2 += w * d * d;
        m0 += w * v[j].p;
        m1 += w * d * v[j].p;
      }
      const double det = s0 * s2 - s1 * s1;
      // A lone annotation (or a window too short for a line) keeps its weighted mean, i.e. itself.
      out[i].p = det > 1e-12 * s0 * s0 ? Eigen::Vector2d((s2 * m0 - s1 * m1) / det) : Eigen::Vector2d(m0 / s0);
    }
    v = std::move(out);
  }
}

namespace {
Eigen::Vector2d secondDifference(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return c - 2.0 * b + a;
}

// The earliest id exchange in `set` (see fixIdExchanges), if any.
std::optional<IdExchange> firstIdExchange(const TrajectorySet& set, const IdExchangeParams& p) {
  // Interior annotations by time (times in microseconds: annotations share a frame clock).
  std::map<long long, std::vector<std::pair<int, std::size_t>>> at;
  for (const auto& [id, v] : set.people)
    for (std::size_t i = 1; i + 1 < v.size(); ++i)
      if (v[i].t - v[i - 1].t <= set.max_gap && v[i + 1].t - v[i].t <= set.max_gap)
        at[std::llround(v[i].t * 1e6)].emplace_back(id, i);
  const double min2 = p.min_second_difference * p.min_second_difference;
  for (const auto& [key, here] : at)
    for (std::size_t x = 0; x < here.size(); ++x)
      for (std::size_t y = x + 1; y < here.size(); ++y) {
        const auto& va = set.people.at(here[x].first);
        const auto& vb = set.people.at(here[y].first);
        const std::size_t i = here[x].second, j = here[y].second;
        if (std::abs(va[i - 1].t - vb[j - 1].t) > 1e-6 || std::abs(va[i + 1].t - vb[j + 1].t) > 1e-6) continue;
        if ((va[i].p - vb[j].p).norm() > p.max_distance) continue;
        const double kept = secondDifference(va[i - 1].p, va[i].p, va[i + 1].p).squaredNorm() +
                            secondDifference(vb[j - 1].p, vb[j].p, vb[j + 1].p).squaredNorm();
        const double exchanged = secondDifference(va[i - 1].p, va[i].p, vb[j + 1].p).squaredNorm() +
                                 secondDifference(vb[j - 1].p, vb[j].p, va[i + 1].p).squaredNorm();
        if (kept > min2 && exchanged < p.ratio * kept) return IdExchange{here[x].first, here[y].first, va[i].t};
      }
  return std::nullopt;
}
}  // namespace

std::vector<IdExchange> fixIdExchanges(TrajectorySet& set, const IdExchangeParams& params) {
  if (!(params.max_distance > 0.0) || !(params.ratio > 0.0 && params.ratio < 1.0) ||
      !(params.min_second_difference >= 0.0) || !std::isfinite(params.max_distance) ||
      !std::isfinite(params.min_second_difference))
    throw InputError("id exchange parameters out of range (max_distance > 0, ratio in (0, 1), min_second_difference >= 0)");
  std::vector<IdExchange> out;
  // Each undone exchange leaves both paths smooth at its time, so it is not found again; the bound is a guard.
  for (std::size_t guard = set.samples(); guard > 0; --guard) {
    const std::optional<IdExchange> e = firstIdExchange(set, params);
    if (!e) break;
    auto& va = set.people.at(e->a);
    auto& vb = set.people.at(e->b);
    auto later = [&](std::vector<TrajectoryPoint>& v) {
      return std::upper_bound(v.begin(), v.end(), e->after, [](double t, const TrajectoryPoint& q) { return t < q.t; });
    };
    std::vector<TrajectoryPoint> tail_a(later(va), va.end()), tail_b(later(vb), vb.end());
    va.erase(later(va), va.end());
    vb.erase(later(vb), vb.end());
    va.insert(va.end(), tail_b.begin(), tail_b.end());
    vb.insert(vb.end(), tail_a.begin(), tail_a.end());
    out.push_back(*e);
  }
  return out;
}

std::size_t TrajectorySet::samples() const {
  std::size_t n = 0;
  for (const auto& [id, v] : people) n += v.size();
  return n;
}

namespace {
[[noreturn]] void bad(const std::string& path, std::size_t line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ": " + what);
}

void finish(TrajectorySet& s, const std::string& path) {
  if (s.people.empty()) throw InputError(path + ": no trajectories");
  s.t_begin = std::numeric_limits<double>::infinity();
  s.t_end = -s.t_begin;
  s.min = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  s.max = -s.min;
  for (auto& [id, v] : s.people) {
    std::stable_sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
    // Drop duplicate stamps (keep the first).
    v.erase(std::unique(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.t == b.t; }), v.end());
    s.t_begin = std::min(s.t_begin, v.front().t);
    s.t_end = std::max(s.t_end, v.back().t);
    for (const auto& p : v) {
      s.min = s.min.cwiseMin(p.p);
      s.max = s.max.cwiseMax(p.p);
    }
  }
}
}  // namespace

TrajectorySet loadTrajectories(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open trajectory file " + path);
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  TrajectorySet s;
  std::istringstream lines(text);
  std::string line;
  std::size_t ln = 0;
  if (text.find("TRACK.") != std::string::npos) {
    s.format = "edinburgh";
    s.max_gap = 1.0;
    constexpr double kMetresPerPixel = 0.0247, kFps = 9.0;
    while (std::getline(lines, line)) {
      ++ln;
      const auto pos = line.find("TRACK.");
      if (pos == std::string::npos) continue;
      // TRACK.R<id> = [[x y t];[x y t];...]; — parsed by hand: a regex over a whole track (one line of up to
      // 82 kB in tracks.01Aug.txt) recursed once per character in libstdc++ and overflowed the stack.
      std::size_t i = pos + 6;
      if (line.compare(i, 1, "R") != 0) bad(path, ln, "malformed TRACK entry (expected TRACK.R<id>)");
      const std::size_t digits = line.find_first_not_of("0123456789", ++i);
      if (digits == i || digits == std::string::npos || digits - i > 9) bad(path, ln, "malformed TRACK entry (bad id)");
      const int id = std::stoi(line.substr(i, digits - i));
      i = line.find_first_not_of(" \t", digits);
      if (i == std::string::npos || line[i] != '=') bad(path, ln, "malformed TRACK entry (expected '=')");
      i = line.find_first_not_of(" \t", i + 1);
      const std::size_t close = line.find_last_of(']');
      if (i == std::string::npos || line[i] != '[' || close == std::string::npos || close <= i ||
          line.find_first_not_of(" \t\r;", close + 1) != std::string::npos)
        bad(path, ln, "malformed TRACK entry (expected [...])");
      if (std::count(line.begin() + static_cast<long>(i), line.begin() + static_cast<long>(close) + 1, '[') !=
          std::count(line.begin() + static_cast<long>(i), line.begin() + static_cast<long>(close) + 1, ']'))
        bad(path, ln, "malformed TRACK entry (unbalanced brackets)");
      std::string body = line.substr(i + 1, close - i - 1);
      std::replace_if(body.begin(), body.end(), [](char c) { return c == '[' || c == ']' || c == ';'; }, ' ');
      std::istringstream nums(body);
      double x, y, t;
      while (nums >> x >> y >> t) s.people[id].push_back({t / kFps, {x * kMetresPerPixel, y * kMetresPerPixel}});
      if (!nums.eof()) bad(path, ln, "non-numeric value in TRACK entry");
    }
  } else if (text.find(',') != std::string::npos) {
    s.format = "csv";
    while (std::getline(lines, line)) {
      ++ln;
      if (line.empty() || line[0] == '#') continue;
      if (ln == 1 && (line.find('t') != std::string::npos || line.find('x') != std::string::npos)) continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream f(line);
      double t, x, y;
      int id;
      if (!(f >> t >> id >> x >> y) || !std::isfinite(t) || !std::isfinite(x) || !std::isfinite(y))
        bad(path, ln, "expected t,id,x,y");
      s.people[id].push_back({t, {x, y}});
    }
  } else {
    s.format = "obsmat";
    struct Row {
      double frame;
      int id;
      double x, y;
    };
    std::vector<Row> rows;
    while (std::getline(lines, line)) {
      ++ln;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::istringstream f(line);
      double frame, id, x, z, y;
      if (!(f >> frame >> id >> x >> z >> y) || !std::isfinite(x) || !std::isfinite(y))
        bad(path, ln, "expected obsmat row 'frame id x z y vx vz vy'");
      rows.push_back({frame, static_cast<int>(id), x, y});
    }
    std::vector<double> frames;
    for (const auto& r : rows) frames.push_back(r.frame);
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    double step = std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i < frames.size(); ++i) step = std::min(step, frames[i] - frames[i - 1]);
    if (!std::isfinite(step)) step = 1.0;
    constexpr double kAnnotationPeriod = 0.4;  // ETH/UCY annotations at 2.5 fps
    for (const auto& r : rows) s.people[r.id].push_back({r.frame / step * kAnnotationPeriod, {r.x, r.y}});
    s.max_gap = 2.5 * kAnnotationPeriod;
  }
  finish(s, path);
  return s;
}

}  // namespace cairn::people_tracking
