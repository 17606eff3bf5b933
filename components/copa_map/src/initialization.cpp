#include "cairn/copa_map/initialization.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>

namespace cairn::copa_map {
namespace {
constexpr double kTwoPi = 6.28318530717958647692;
}

std::vector<std::complex<double>> nudft(const Eigen::VectorXd& t, const Eigen::VectorXd& y,
                                        const std::vector<double>& periods, double mean) {
  std::vector<std::complex<double>> xi(periods.size());
  const double J = static_cast<double>(t.size());
  for (std::size_t k = 0; k < periods.size(); ++k) {
    std::complex<double> s = 0;
    for (Eigen::Index j = 0; j < t.size(); ++j)
      s += (y[j] - mean) * std::polar(1.0, -kTwoPi * t[j] / periods[k]);  // eq. 4.17
    xi[k] = s / J;
  }
  return xi;
}

Eigen::VectorXd fourierReconstruct(const Eigen::VectorXd& t, double mean,
                                   const std::vector<std::complex<double>>& xi, const std::vector<double>& periods) {
  Eigen::VectorXd out = Eigen::VectorXd::Constant(t.size(), mean);
  for (std::size_t u = 0; u < xi.size(); ++u)
    for (Eigen::Index j = 0; j < t.size(); ++j)
      out[j] += 2.0 * std::abs(xi[u]) * std::cos(kTwoPi * t[j] / periods[u] + std::arg(xi[u]));  // eq. 4.18
  return out;
}

KMeansResult weightedKMeans(const Eigen::MatrixXd& P, const Eigen::VectorXd& w, int k, int max_iter,
                            std::uint64_t seed) {
  const Eigen::Index n = P.rows(), d = P.cols();
  if (n == 0 || k <= 0) throw std::invalid_argument("weightedKMeans: no points or k <= 0");
  if (w.size() != n || (w.array() < 0).any() || !w.allFinite())
    throw std::invalid_argument("weightedKMeans: weights must be finite, non-negative, one per point");
  k = static_cast<int>(std::min<Eigen::Index>(k, n));
  std::mt19937_64 rng(seed);
  KMeansResult r;
  r.centers.resize(k, d);
  // k-means++ seeding, sampling proportional to w_i * D(x_i)².
  Eigen::VectorXd wpos = w;
  if (wpos.sum() <= 0) wpos.setOnes();
  std::discrete_distribution<Eigen::Index> first(wpos.data(), wpos.data() + n);
  r.centers.row(0) = P.row(first(rng));
  Eigen::VectorXd dist = (P.rowwise() - r.centers.row(0)).rowwise().squaredNorm();
  for (int c = 1; c < k; ++c) {
    Eigen::VectorXd p = wpos.cwiseProduct(dist);
    Eigen::Index pick;
    if (p.sum() <= 0) {
      std::uniform_int_distribution<Eigen::Index> u(0, n - 1);
      pick = u(rng);
    } else {
      std::uniform_real_distribution<double> u(0.0, p.sum());
      double target = u(rng), acc = 0;
      pick = n - 1;
      for (Eigen::Index i = 0; i < n; ++i) {
        acc += p[i];
        if (acc >= target) {
          pick = i;
          break;
        }
      }
    }
    r.centers.row(c) = P.row(pick);
    dist = dist.cwiseMin((P.rowwise() - r.centers.row(c)).rowwise().squaredNorm());
  }
  r.labels.assign(static_cast<std::size_t>(n), 0);
  const bool par = static_cast<double>(n) * k > 1e6;
  for (int it = 0; it < max_iter; ++it) {
    bool changed = false;
    double inertia = 0;
#pragma omp parallel for schedule(static) reduction(|| : changed) reduction(+ : inertia) if (par)
    for (Eigen::Index i = 0; i < n; ++i) {
      int best = 0;
      double bd = std::numeric_limits<double>::infinity();
      for (int c = 0; c < k; ++c) {
        const double dd = (P.row(i) - r.centers.row(c)).squaredNorm();
        if (dd < bd) {
          bd = dd;
          best = c;
        }
      }
      if (r.labels[static_cast<std::size_t>(i)] != best || it == 0) changed = true;
      r.labels[static_cast<std::size_t>(i)] = best;
      inertia += w[i] * bd;
    }
    r.inertia = inertia;
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(k, d);
    Eigen::VectorXd ws = Eigen::VectorXd::Zero(k);
    for (Eigen::Index i = 0; i < n; ++i) {
      sum.row(r.labels[static_cast<std::size_t>(i)]) += w[i] * P.row(i);
      ws[r.labels[static_cast<std::size_t>(i)]] += w[i];
    }
    for (int c = 0; c < k; ++c)
      if (ws[c] > 0) r.centers.row(c) = sum.row(c) / ws[c];  // empty / zero-weight clusters keep their centre
    if (!changed) break;
  }
  return r;
}

Eigen::MatrixXd initializeInducing(const Eigen::MatrixXd& X, const Eigen::VectorXd& durations, double alpha,
                                   int max_iter, std::uint64_t seed) {
  if (!(alpha > 0) || alpha > 1) throw std::invalid_argument("initializeInducing: α_ind must be in (0, 1]");
  const int m = std::max(1, static_cast<int>(std::floor(alpha * static_cast<double>(X.rows()))));
  const Eigen::VectorXd w = durations.size() == X.rows() ? durations : Eigen::VectorXd::Ones(X.rows());
  return weightedKMeans(X, w, m, max_iter, seed).centers;
}

PeriodInitResult initializePeriods(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                   const Eigen::VectorXd& counts, const PeriodInitConfig& cfg) {
  if (X.rows() == 0 || X.rows() != y.size()) throw std::invalid_argument("initializePeriods: empty or mismatched data");
  if (!(cfg.period_step > 0) || !(cfg.period_min > 0) || !(cfg.cell_size > 0) || !(cfg.time_bin > 0))
    throw std::invalid_argument(
        "initializePeriods: period_step, period_min, cell_size and time_bin must be > 0");
  // Collapse the data onto the coarse initialization grid; one time series per spatial cell (mean rate per bin).
  struct Series {
    std::map<long long, std::pair<double, int>> bins;  // time bin -> (sum y, n)
    double weight = 0;
  };
  std::map<std::pair<long long, long long>, Series> cells;
  const double tmin = X.col(2).minCoeff(), tmax = X.col(2).maxCoeff();
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const auto key = std::make_pair(static_cast<long long>(std::floor(X(i, 0) / cfg.cell_size)),
                                    static_cast<long long>(std::floor(X(i, 1) / cfg.cell_size)));
    Series& s = cells[key];
    auto& b = s.bins[static_cast<long long>(std::floor((X(i, 2) - tmin) / cfg.time_bin))];
    b.first += y[i];
    b.second += 1;
    s.weight += counts.size() == y.size() ? counts[i] : y[i];
  }
  std::vector<Eigen::VectorXd> ts, ys;
  std::vector<double> weights;
  for (const auto& [key, s] : cells) {
    if (static_cast<int>(s.bins.size()) < cfg.min_series_length) continue;
    Eigen::VectorXd t(static_cast<Eigen::Index>(s.bins.size())), v(t.size());
    Eigen::Index j = 0;
    for (const auto& [b, sv] : s.bins) {
      t[j] = tmin + static_cast<double>(b) * cfg.time_bin;
      v[j] = sv.first / sv.second;
      ++j;
    }
    ts.push_back(t);
    ys.push_back(v);
    weights.push_back(std::max(0.0, s.weight));
  }
  if (ts.empty()) throw std::invalid_argument("initializePeriods: no time series long enough");

  // Candidate periods o, equally spaced.
  const double pmax = cfg.period_max > 0 ? cfg.period_max : std::max(cfg.period_min, 0.5 * (tmax - tmin));
  constexpr double kMaxCandidates = 1e6;
  if (!((pmax - cfg.period_min) / cfg.period_step <= kMaxCandidates))
    throw std::invalid_argument(
        "initializePeriods: (period_max - period_min) / period_step gives more than 1e6 "
        "candidate periods (raise period_step)");
  std::vector<double> periods;
  // Indexed, not accumulated: p += step stops advancing when step is below p's rounding unit.
  for (long i = 0;; ++i) {
    const double p = cfg.period_min + static_cast<double>(i) * cfg.period_step;
    if (!(p <= pmax + 1e-9)) break;
    periods.push_back(p);
  }
  if (periods.empty()) throw std::invalid_argument("initializePeriods: empty candidate period set");

  // Roulette-wheel selection of Λ series weighted by total counts (without replacement).
  std::mt19937_64 rng(cfg.seed);
  std::vector<std::size_t> chosen;
  std::vector<double> wleft = weights;
  if (std::accumulate(wleft.begin(), wleft.end(), 0.0) <= 0) std::fill(wleft.begin(), wleft.end(), 1.0);
  for (int l = 0; l < cfg.num_series && chosen.size() < ts.size(); ++l) {
    const double total = std::accumulate(wleft.begin(), wleft.end(), 0.0);
    if (total <= 0) break;
    std::uniform_real_distribution<double> u(0.0, total);
    double target = u(rng), acc = 0;
    std::size_t pick = wleft.size() - 1;
    for (std::size_t i = 0; i < wleft.size(); ++i) {
      acc += wleft[i];
      if (acc >= target && wleft[i] > 0) {
        pick = i;
        break;
      }
    }
    chosen.push_back(pick);
    wleft[pick] = 0;
  }

  PeriodInitResult res;
  for (std::size_t sidx : chosen) {
    const Eigen::VectorXd& t = ts[sidx];
    const Eigen::VectorXd& v = ys[sidx];
    const Eigen::Index J = t.size();
    double best_err = std::numeric_limits<double>::infinity();
    int best_b = 0;
    std::vector<std::complex<double>> best_xi;
    std::vector<double> best_o;
    for (int fold = 0; fold < cfg.folds; ++fold) {  // Algorithm 4.1, lines 2-9: contiguous folds
      const Eigen::Index a = fold * J / cfg.folds, b = (fold + 1) * J / cfg.folds;
      if (b <= a) continue;
      Eigen::VectorXd ttr(J - (b - a)), ytr(J - (b - a));
      Eigen::Index q = 0;
      for (Eigen::Index j = 0; j < J; ++j)
        if (j < a || j >= b) {
          ttr[q] = t[j];
          ytr[q] = v[j];
          ++q;
        }
      if (q < 2) continue;
      const double mean = ytr.mean();
      const auto xi = nudft(ttr, ytr, periods, mean);
      // Most prominent components = spectral peaks (local maxima of |ξ| over the candidate grid) by magnitude;
      // this keeps one component per peak instead of its leakage neighbours.
      std::vector<std::size_t> peaks;
      for (std::size_t k = 0; k < xi.size(); ++k) {
        const double mk = std::abs(xi[k]);
        const bool left = k == 0 || mk >= std::abs(xi[k - 1]);
        const bool right = k + 1 == xi.size() || mk > std::abs(xi[k + 1]);
        if (left && right) peaks.push_back(k);
      }
      std::sort(peaks.begin(), peaks.end(), [&](std::size_t x, std::size_t y2) { return std::abs(xi[x]) > std::abs(xi[y2]); });
      const Eigen::VectorXd tts = t.segment(a, b - a), yts = v.segment(a, b - a);
      for (int nb = 0; nb <= cfg.max_periods && nb <= static_cast<int>(peaks.size()); ++nb) {
        std::vector<std::complex<double>> xb;
        std::vector<double> ob;
        for (int u = 0; u < nb; ++u) {
          xb.push_back(xi[peaks[static_cast<std::size_t>(u)]]);
          ob.push_back(periods[peaks[static_cast<std::size_t>(u)]]);
        }
        const double err = std::sqrt((fourierReconstruct(tts, mean, xb, ob) - yts).squaredNorm() / (b - a));
        if (err < best_err) {  // line 10: argmin over folds and b
          best_err = err;
          best_b = nb;
          best_xi = xb;
          best_o = ob;
        }
      }
    }
    res.chosen_b.push_back(best_b);
    for (std::size_t u = 0; u < best_xi.size(); ++u) {  // lines 11-12
      res.all_periods.push_back(best_o[u]);
      res.all_weights.push_back(std::abs(best_xi[u]));
    }
  }
  // Line 13: ψ = ⌊mean b_l⌋ (at least one component so that k_f keeps a temporal part).
  const double mean_b = res.chosen_b.empty() ? 0.0
                                             : std::accumulate(res.chosen_b.begin(), res.chosen_b.end(), 0.0) /
                                                   static_cast<double>(res.chosen_b.size());
  int psi = std::max(1, static_cast<int>(std::floor(mean_b)));
  if (res.all_periods.empty()) {
    // No series preferred any periodic component: fall back to the strongest single period of the first series.
    res.periods = {periods.back()};
    res.variances = {cfg.max_variance};
    return res;
  }
  psi = std::min<int>(psi, static_cast<int>(res.all_periods.size()));
  // Line 14: weighted k-means (k = ψ) of the chosen periods, weights = magnitudes.
  Eigen::MatrixXd P(static_cast<Eigen::Index>(res.all_periods.size()), 1);
  Eigen::VectorXd w(P.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    P(i, 0) = res.all_periods[static_cast<std::size_t>(i)];
    w[i] = res.all_weights[static_cast<std::size_t>(i)];
  }
  const KMeansResult km = weightedKMeans(P, w, psi, 100, cfg.seed);
  Eigen::VectorXd sumw = Eigen::VectorXd::Zero(km.centers.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) sumw[km.labels[static_cast<std::size_t>(i)]] += w[i];
  // Line 15: summed cluster weights normalized to [0, σ²_max]; order by variance, largest first.
  std::vector<int> order(static_cast<std::size_t>(km.centers.rows()));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return sumw[a] > sumw[b]; });
  const double wmax = std::max(sumw.maxCoeff(), 1e-300);
  for (int c : order) {
    if (sumw[c] <= 0) continue;
    res.periods.push_back(km.centers(c, 0));
    res.variances.push_back(cfg.max_variance * sumw[c] / wmax);
  }
  return res;
}

}  // namespace cairn::copa_map
