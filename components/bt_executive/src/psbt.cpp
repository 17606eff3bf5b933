#include "cairn/bt_executive/psbt.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace cairn::bt::psbt {

double GridModel::integrateDisc(const Eigen::Vector2d& c, double r) const {
  const int i0 = std::max(0, static_cast<int>(std::floor((c.x() - r) / resolution)));
  const int i1 = std::min(width() - 1, static_cast<int>(std::floor((c.x() + r) / resolution)));
  const int j0 = std::max(0, static_cast<int>(std::floor((c.y() - r) / resolution)));
  const int j1 = std::min(height() - 1, static_cast<int>(std::floor((c.y() + r) / resolution)));
  const double r2 = r * r, area = resolution * resolution;
  double sum = 0.0;
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j)
      if ((cellCenter(i, j) - c).squaredNorm() <= r2 + 1e-12) sum += rate(i, j) * area;
  return sum;
}

GridModel syntheticHotspots(double width_m, double height_m, double resolution, int hotspots, std::uint64_t seed) {
  GridModel m;
  m.resolution = resolution;
  const int w = static_cast<int>(std::round(width_m / resolution)), h = static_cast<int>(std::round(height_m / resolution));
  m.rate = Eigen::MatrixXd::Constant(w, h, 2e-4);  // background: a passer-by every ~7 min in a 2 m disc
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(0, width_m), uy(0, height_m), upeak(1e-3, 6e-3), usig(1.5, 4.0);
  for (int k = 0; k < hotspots; ++k) {
    const Eigen::Vector2d c(ux(rng), uy(rng));
    const double peak = upeak(rng), s = usig(rng);
    for (int i = 0; i < w; ++i)
      for (int j = 0; j < h; ++j) m.rate(i, j) += peak * std::exp(-(m.cellCenter(i, j) - c).squaredNorm() / (2 * s * s));
  }
  return m;
}

ActionStats waitAction(const GridModel& m, const Eigen::Vector2d& x, const Params& p) {
  ActionStats a;
  const double mu = m.integrateDisc(x, p.r_D);  // eq. 5.9
  if (mu <= 0) {
    a.p_s = 0.0;
    a.mu = 1.0;
    a.nu = 1e-9;
    return a;
  }
  const double t_wait = -std::log(1.0 - p.p_conf) / mu;  // eq. 5.11: T' = nu_w^-1
  a.p_s = p.p_conf;                                       // eq. 5.12: fails with 1 - p'_s after T'
  a.mu = mu;
  a.nu = 1.0 / t_wait;
  return a;
}

ActionStats searchAction(const GridModel& m, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Params& p) {
  ActionStats s;
  s.length = (b - a).norm();
  const double T = s.length / p.v;
  s.nu = p.v / std::max(s.length, 1e-9) + p.v / p.l_fail;  // eq. 5.17
  const double t_end = std::min(1.0 / s.nu, T);
  double best_inv = std::numeric_limits<double>::infinity();
  double integral = 0.0;
  const int K = static_cast<int>(std::ceil(T / p.dt));
  for (int k = 0; k <= K; ++k) {
    const double tk = std::min(k * p.dt, T);
    const Eigen::Vector2d x = T > 0 ? Eigen::Vector2d(a + (b - a) * (tk / T)) : a;
    const double mu_k = m.integrateDisc(x, p.r_D);  // eq. 5.14, discretized with t_k = k Δt
    if (mu_k > 0) best_inv = std::min(best_inv, tk - std::log(1.0 - p.p_conf) / mu_k);  // eq. 5.15
    if (tk < t_end) integral += mu_k * std::min(p.dt, t_end - tk);
  }
  s.mu = std::isfinite(best_inv) ? 1.0 / best_inv : 1.0;
  s.p_s = 1.0 - std::exp(-integral);  // eq. 5.16 at t = nu_sp^-1 (p_f of eq. 5.18 is 1 - p_s there)
  return s;
}

ActionStats moveAction(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Params& p) {
  return moveAction((b - a).norm(), p);
}

ActionStats moveAction(double length, const Params& p) {
  ActionStats s;
  s.length = length;
  s.p_s = std::exp(-s.length / p.l_fail);  // exponential distance to a navigation failure
  s.mu = s.length > 0 ? p.v / s.length : 1e3;
  s.nu = p.v / p.l_fail;
  return s;
}

std::vector<Eigen::Vector2d> samplePlaces(const GridModel& m, const Eigen::Vector2d& start, const Params& p,
                                          std::mt19937_64& rng, bool uniform) {
  std::vector<std::pair<int, int>> cells;
  std::vector<double> weights;
  for (int i = 0; i < m.width(); ++i)
    for (int j = 0; j < m.height(); ++j) {
      const Eigen::Vector2d c = m.cellCenter(i, j);
      const double d = (c - start).norm();
      if (d > p.max_distance || d < p.r_D) continue;  // the help location itself is covered by waiting there
      cells.emplace_back(i, j);
      weights.push_back(uniform ? 1.0 : m.rate(i, j));
    }
  std::vector<Eigen::Vector2d> out;
  std::vector<double> out_rate;
  if (cells.empty()) return out;
  std::discrete_distribution<std::size_t> pick(weights.begin(), weights.end());
  for (int k = 0; k < p.sample_attempts && static_cast<int>(out.size()) < p.n_pl; ++k) {
    auto [i, j] = cells[pick(rng)];
    const Eigen::Vector2d c = m.cellCenter(i, j);
    // Deduplicate (§5.4.3: of close cells only the one with the larger rate is kept): a cell within r_D of kept
    // places replaces all of them if its rate is larger than each of theirs, else it is dropped. (Replacing only
    // the first close place could leave the new one within r_D of another.)
    const double rate = m.rate(i, j);
    bool larger = true, close = false;
    for (std::size_t q = 0; q < out.size(); ++q)
      if ((out[q] - c).norm() < p.r_D) {
        close = true;
        larger = larger && rate > out_rate[q];
      }
    if (close && !larger) continue;
    for (std::size_t q = out.size(); q-- > 0;)
      if ((out[q] - c).norm() < p.r_D) {
        out.erase(out.begin() + static_cast<std::ptrdiff_t>(q));
        out_rate.erase(out_rate.begin() + static_cast<std::ptrdiff_t>(q));
      }
    out.push_back(c);
    out_rate.push_back(rate);
  }
  return out;
}

double tourCost(const Eigen::MatrixXd& cost, const std::vector<int>& order) {
  double c = 0;
  int prev = 0;
  for (int v : order) {
    c += cost(prev, v);
    prev = v;
  }
  return c;
}

std::vector<int> openTsp(const Eigen::MatrixXd& cost, std::uint64_t seed) {
  const int n = static_cast<int>(cost.rows());
  if (n <= 1) return {};
  const int m = n - 1;  // nodes 1..n-1
  if (m <= 12) {
    // Held-Karp over subsets of the m places; path starts at 0 and may end anywhere.
    const int full = 1 << m;
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> dp(static_cast<std::size_t>(full) * m, inf);
    std::vector<int> parent(static_cast<std::size_t>(full) * m, -1);
    auto at = [m](int s, int j) { return static_cast<std::size_t>(s) * m + j; };
    for (int j = 0; j < m; ++j) dp[at(1 << j, j)] = cost(0, j + 1);
    for (int s = 1; s < full; ++s)
      for (int j = 0; j < m; ++j) {
        if (!(s & (1 << j)) || dp[at(s, j)] == inf) continue;
        for (int k = 0; k < m; ++k) {
          if (s & (1 << k)) continue;
          const int t = s | (1 << k);
          const double c = dp[at(s, j)] + cost(j + 1, k + 1);
          if (c < dp[at(t, k)]) {
            dp[at(t, k)] = c;
            parent[at(t, k)] = j;
          }
        }
      }
    int best = 0;
    for (int j = 1; j < m; ++j)
      if (dp[at(full - 1, j)] < dp[at(full - 1, best)]) best = j;
    std::vector<int> order;
    for (int s = full - 1, j = best; j >= 0;) {
      order.push_back(j + 1);
      const int pj = parent[at(s, j)];
      s &= ~(1 << j);
      j = pj;
    }
    std::reverse(order.begin(), order.end());
    return order;
  }
  // Genetic algorithm (order crossover + swap/reversal mutation, elitism), as in [Dav10] / §5.4.3.
  std::mt19937_64 rng(seed);
  const int pop = 60, generations = 400;
  std::vector<std::vector<int>> P(pop);
  std::vector<int> base(m);
  std::iota(base.begin(), base.end(), 1);
  for (auto& ind : P) {
    ind = base;
    std::shuffle(ind.begin(), ind.end(), rng);
  }
  auto fitness = [&](const std::vector<int>& o) { return tourCost(cost, o); };
  std::uniform_int_distribution<int> ui(0, m - 1), up(0, pop - 1);
  std::uniform_real_distribution<double> u01(0, 1);
  for (int g = 0; g < generations; ++g) {
    std::sort(P.begin(), P.end(), [&](auto& a, auto& b) { return fitness(a) < fitness(b); });
    std::vector<std::vector<int>> next(P.begin(), P.begin() + pop / 5);
    while (static_cast<int>(next.size()) < pop) {
      auto tour = [&]() -> const std::vector<int>& {
        const int a = up(rng), b = up(rng);
        return fitness(P[a]) < fitness(P[b]) ? P[a] : P[b];
      };
      const auto& pa = tour();
      const auto& pb = tour();
      int i = ui(rng), j = ui(rng);
      if (i > j) std::swap(i, j);
      std::vector<int> child(m, -1);
      std::vector<char> used(static_cast<std::size_t>(n), 0);
      for (int k = i; k <= j; ++k) {
        child[k] = pa[k];
        used[pa[k]] = 1;
      }
      int pos = (j + 1) % m;
      for (int k = 0; k < m; ++k) {
        const int gene = pb[(j + 1 + k) % m];
        if (used[gene]) continue;
        child[pos] = gene;
        pos = (pos + 1) % m;
      }
      if (u01(rng) < 0.3) std::swap(child[ui(rng)], child[ui(rng)]);
      if (u01(rng) < 0.3) {
        int a = ui(rng), b = ui(rng);
        if (a > b) std::swap(a, b);
        std::reverse(child.begin() + a, child.begin() + b + 1);
      }
      next.push_back(std::move(child));
    }
    P = std::move(next);
  }
  return *std::min_element(P.begin(), P.end(), [&](auto& a, auto& b) { return fitness(a) < fitness(b); });
}

namespace {
std::string pname(int k) {
  std::string s("x");
  s.append(std::to_string(k));
  return s;
}
std::string label(const char* kind, int from, int to) {
  std::string s(kind);
  if (from >= 0) s.append(pname(from)).append("->");
  s.append(pname(to));
  return s;
}
}  // namespace

sbt::Node buildTree(const GridModel& m, const Eigen::Vector2d& start, const std::vector<Eigen::Vector2d>& places,
                    bool wait_at_start, const std::vector<int>& choice, const Params& p) {
  std::vector<sbt::Node> acts;
  // The return to x0 (Fig. 5.9) starts where the person was found (§5.4.4: 1/μ_T is the time "to find a person and
  // then return"). Its length is the expected distance from x0 of the place where the search succeeds: each action
  // weighted by the probability that it is the one that succeeds (its p_s after all earlier ones failed); a
  // person found on the path to a place is counted at that place (an approximation). It used to be measured from
  // the tour's last place, which is optimistic for a tour ending near x0.
  double p_none = 1.0, w_sum = 0.0, d_sum = 0.0;
  auto succeedsAt = [&](double p_s, const Eigen::Vector2d& x) {
    const double w = p_none * p_s;
    w_sum += w;
    d_sum += w * (x - start).norm();
    p_none *= 1.0 - p_s;
  };
  if (wait_at_start) {
    const auto w = waitAction(m, start, p);
    acts.push_back(sbt::action("Wait:x0", w.p_s, w.mu, w.nu));
    succeedsAt(w.p_s, start);
  }
  Eigen::Vector2d prev = start;
  int prev_id = 0;
  for (std::size_t k = 0; k < places.size() && k < choice.size(); ++k) {
    if (choice[k] == 0) continue;
    const auto s = searchAction(m, prev, places[k], p);
    acts.push_back(sbt::action(label("Search:", prev_id, static_cast<int>(k) + 1), s.p_s, s.mu, s.nu));
    succeedsAt(s.p_s, places[k]);
    prev = places[k];
    prev_id = static_cast<int>(k) + 1;
    if (choice[k] == 2) {
      const auto w = waitAction(m, places[k], p);
      acts.push_back(sbt::action(label("Wait:", -1, prev_id), w.p_s, w.mu, w.nu));
      succeedsAt(w.p_s, places[k]);
    }
  }
  if (acts.empty()) throw std::invalid_argument("empty person-search plan");
  sbt::Node search = acts.size() == 1 ? acts.front() : sbt::fallback(std::move(acts), "search");
  if (prev_id == 0) return search;
  const auto mv = w_sum > 0 ? moveAction(d_sum / w_sum, p) : moveAction(prev, start, p);
  return sbt::sequence({std::move(search), sbt::action("MoveTo:x0", mv.p_s, mv.mu, mv.nu)}, "psbt");
}

namespace {

Plan evaluate(const GridModel& m, const Eigen::Vector2d& start, std::vector<Eigen::Vector2d> places, bool ws,
              std::vector<int> choice, const Params& p, bool rates = true) {
  Plan pl;
  pl.wait_at_start = ws;
  pl.choice = std::move(choice);
  pl.places = std::move(places);
  pl.tree = buildTree(m, start, pl.places, ws, pl.choice, p);
  sbt::Analysis a(pl.tree);
  pl.p_success_tmax = a.successProbability(p.t_max);
  if (rates) pl.mu_T = a.successRate();
  return pl;
}

std::vector<Eigen::Vector2d> ordered(const std::vector<Eigen::Vector2d>& places, const Eigen::Vector2d& start,
                                     const Params& p) {
  // Costs: expected times to fail nu_s,i->j^-1 of the search paths (§5.4.3).
  const int n = static_cast<int>(places.size()) + 1;
  Eigen::MatrixXd cost(n, n);
  auto pos = [&](int i) { return i == 0 ? start : places[static_cast<std::size_t>(i - 1)]; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double l = (pos(i) - pos(j)).norm();
      cost(i, j) = i == j ? 0.0 : 1.0 / (p.v / std::max(l, 1e-9) + p.v / p.l_fail);
    }
  std::vector<Eigen::Vector2d> out;
  for (int k : openTsp(cost)) out.push_back(pos(k));
  return out;
}

}  // namespace

Synthesis synthesize(const GridModel& m, const Eigen::Vector2d& start, const Params& p, std::mt19937_64& rng) {
  Synthesis s;
  s.sampled = samplePlaces(m, start, p, rng);
  const auto places = ordered(s.sampled, start, p);
  const int n = static_cast<int>(places.size());
  int combos = 1;
  for (int k = 0; k < n; ++k) combos *= 3;
  bool have = false;
  for (int ws = 0; ws < 2; ++ws)
    for (int code = 0; code < combos; ++code) {
      if (!ws && code == 0) continue;  // nothing to do
      std::vector<int> choice(static_cast<std::size_t>(n));
      for (int k = 0, c = code; k < n; ++k, c /= 3) choice[static_cast<std::size_t>(k)] = c % 3;
      Plan pl = evaluate(m, start, places, ws == 1, std::move(choice), p, false);
      ++s.candidates;
      if (!have || pl.p_success_tmax > s.best.p_success_tmax + 1e-12) {
        s.best = std::move(pl);
        have = true;
      }
    }
  s.best.mu_T = sbt::Analysis(s.best.tree).successRate();
  return s;
}

const char* toString(Baseline b) {
  switch (b) {
    case Baseline::GM: return "GM";
    case Baseline::GC: return "GC";
    case Baseline::RND: return "RND";
    case Baseline::W: return "W";
    case Baseline::PP: return "PP";
  }
  return "?";
}

Plan baseline(Baseline b, const GridModel& m, const Eigen::Vector2d& start, const Params& p, std::mt19937_64& rng,
              int n_lambda) {
  switch (b) {
    case Baseline::W: return evaluate(m, start, {}, true, {}, p);
    case Baseline::GM:
    case Baseline::GC: {
      std::vector<std::pair<double, Eigen::Vector2d>> cells;
      for (int i = 0; i < m.width(); ++i)
        for (int j = 0; j < m.height(); ++j) cells.push_back({m.rate(i, j), m.cellCenter(i, j)});
      std::sort(cells.begin(), cells.end(), [](auto& a, auto& c) { return a.first > c.first; });
      Eigen::Vector2d goal = cells.front().second;
      if (b == Baseline::GC) {
        const int k = std::min<int>(n_lambda, static_cast<int>(cells.size()));
        double best = std::numeric_limits<double>::infinity();
        for (int i = 0; i < k; ++i)
          if ((cells[i].second - start).norm() < best) {
            best = (cells[i].second - start).norm();
            goal = cells[i].second;
          }
      }
      if ((goal - start).norm() < 1e-9) return evaluate(m, start, {}, true, {}, p);
      return evaluate(m, start, {goal}, false, {2}, p);
    }
    case Baseline::RND:
    case Baseline::PP: {
      const auto places = ordered(samplePlaces(m, start, p, rng, b == Baseline::RND), start, p);
      if (places.empty()) return evaluate(m, start, {}, true, {}, p);
      std::vector<int> choice(places.size(), 1);
      std::bernoulli_distribution coin(0.5);
      if (b == Baseline::RND)
        for (auto& c : choice) c = coin(rng) ? 2 : 1;
      return evaluate(m, start, places, false, choice, p);
    }
  }
  throw std::invalid_argument("unknown baseline");
}

std::string toXml(const GridModel& m, const Eigen::Vector2d& start, const Plan& plan, const Params& p) {
  std::ostringstream os;
  os.precision(4);
  auto wait = [&](const Eigen::Vector2d& x) {
    const auto w = waitAction(m, x, p);
    const long ms = w.p_s > 0 ? static_cast<long>(std::lround(1000.0 / w.nu)) : static_cast<long>(p.t_max * 1000);
    os << "          <WaitForPerson x=\"" << x.x() << "\" y=\"" << x.y() << "\" timeout_ms=\"" << ms << "\"/>\n";
  };
  os << "<root BTCPP_format=\"4\">\n  <BehaviorTree ID=\"PersonSearch\">\n    <Sequence>\n"
     << "      <Fallback name=\"search\">\n";
  if (plan.wait_at_start) wait(start);
  Eigen::Vector2d last = start;
  for (std::size_t k = 0; k < plan.places.size() && k < plan.choice.size(); ++k) {
    if (plan.choice[k] == 0) continue;
    const auto& x = plan.places[k];
    os << "          <SearchPerson x=\"" << x.x() << "\" y=\"" << x.y() << "\"/>\n";
    last = x;
    if (plan.choice[k] == 2) wait(x);
  }
  os << "      </Fallback>\n";
  if ((last - start).norm() > 1e-9)
    os << "      <MoveTo x=\"" << start.x() << "\" y=\"" << start.y() << "\"/>\n";
  os << "    </Sequence>\n  </BehaviorTree>\n</root>\n";
  return os.str();
}

}  // namespace cairn::bt::psbt
