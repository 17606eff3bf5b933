#include "cairn/copa_map/baselines.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "cairn/copa_map/initialization.hpp"

namespace cairn::copa_map {

CellKey MlBaseline::key(double x1, double x2) const {
  return {static_cast<long long>(std::floor(x1 / cell_size_)), static_cast<long long>(std::floor(x2 / cell_size_))};
}

void MlBaseline::fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) {
  if (X.rows() == 0 || X.rows() != y.size()) throw std::invalid_argument("ML baseline: empty or mismatched data");
  std::map<CellKey, std::pair<double, int>> acc;
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    auto& a = acc[key(X(i, 0), X(i, 1))];
    a.first += y[i];
    a.second += 1;
  }
  mean_.clear();
  for (const auto& [k, a] : acc) mean_[k] = a.first / a.second;
  global_ = y.mean();
}

RatePrediction MlBaseline::predict(const Eigen::MatrixXd& X) const {
  RatePrediction p;
  p.mean.resize(X.rows());
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const auto it = mean_.find(key(X(i, 0), X(i, 1)));
    p.mean[i] = it == mean_.end() ? global_ : it->second;
  }
  return p;
}

CellKey FremenBaseline::key(double x1, double x2) const {
  return {static_cast<long long>(std::floor(x1 / cfg_.cell_size)),
          static_cast<long long>(std::floor(x2 / cfg_.cell_size))};
}

void FremenBaseline::fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& durations) {
  if (X.rows() == 0 || X.rows() != y.size()) throw std::invalid_argument("FreMEn baseline: empty or mismatched data");
  const bool have_d = durations.size() == X.rows();
  struct Series {
    std::vector<double> t, y, d;
  };
  std::map<CellKey, Series> series;
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    Series& s = series[key(X(i, 0), X(i, 1))];
    s.t.push_back(X(i, 2));
    s.y.push_back(y[i]);
    s.d.push_back(have_d ? durations[i] : 1.0);
  }
  const double span = X.col(2).maxCoeff() - X.col(2).minCoeff() + 1.0;
  const double base = cfg_.base_period > 0 ? cfg_.base_period : span;
  std::vector<double> periods;
  for (int i = 1; i <= cfg_.num_candidates; ++i) periods.push_back(base / i);  // FreMEn: base period / i
  global_ = y.mean();
  cells_.clear();
  for (auto& [k, s] : series) {
    // Sort by time (contiguous folds).
    std::vector<std::size_t> idx(s.t.size());
    std::iota(idx.begin(), idx.end(), 0);
    std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return s.t[a] < s.t[b]; });
    const Eigen::Index J = static_cast<Eigen::Index>(idx.size());
    Eigen::VectorXd t(J), v(J), d(J);
    for (Eigen::Index j = 0; j < J; ++j) {
      t[j] = s.t[idx[static_cast<std::size_t>(j)]];
      v[j] = s.y[idx[static_cast<std::size_t>(j)]];
      d[j] = s.d[idx[static_cast<std::size_t>(j)]];
    }
    auto staticRate = [&](const Eigen::VectorXd& vv, const Eigen::VectorXd& dd) {
      return (cfg_.prior_shape + vv.dot(dd)) / (cfg_.prior_rate + dd.sum());  // Gamma–Poisson posterior mean
    };
    auto fitOrder = [&](const Eigen::VectorXd& tt, const Eigen::VectorXd& vv, const Eigen::VectorXd& dd, int b,
                        Cell& out) {
      out.rate = staticRate(vv, dd);
      const auto xi = nudft(tt, vv, periods, out.rate);
      std::vector<std::size_t> order(xi.size());
      std::iota(order.begin(), order.end(), 0);
      std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t c) { return std::abs(xi[a]) > std::abs(xi[c]); });
      out.xi.clear();
      out.periods.clear();
      for (int u = 0; u < b && u < static_cast<int>(order.size()); ++u) {
        out.xi.push_back(xi[order[static_cast<std::size_t>(u)]]);
        out.periods.push_back(periods[order[static_cast<std::size_t>(u)]]);
      }
    };
    int best_b = 0;
    if (J >= 2 * cfg_.folds) {
      std::vector<double> err(static_cast<std::size_t>(cfg_.max_order + 1), 0.0);
      for (int f = 0; f < cfg_.folds; ++f) {
        const Eigen::Index a = f * J / cfg_.folds, b = (f + 1) * J / cfg_.folds;
        Eigen::VectorXd tt(J - (b - a)), vv(tt.size()), dd(tt.size());
        Eigen::Index q = 0;
        for (Eigen::Index j = 0; j < J; ++j)
          if (j < a || j >= b) {
            tt[q] = t[j];
            vv[q] = v[j];
            dd[q] = d[j];
            ++q;
          }
        for (int ord = 0; ord <= cfg_.max_order; ++ord) {
          Cell c;
          fitOrder(tt, vv, dd, ord, c);
          const Eigen::VectorXd pred =
              fourierReconstruct(t.segment(a, b - a), c.rate, c.xi, c.periods).cwiseMax(0.0);
          err[static_cast<std::size_t>(ord)] += (pred - v.segment(a, b - a)).squaredNorm();
        }
      }
      best_b = static_cast<int>(std::min_element(err.begin(), err.end()) - err.begin());
    }
    Cell c;
    fitOrder(t, v, d, best_b, c);
    cells_[k] = c;
  }
}

RatePrediction FremenBaseline::predict(const Eigen::MatrixXd& X) const {
  RatePrediction p;
  p.mean.resize(X.rows());
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const auto it = cells_.find(key(X(i, 0), X(i, 1)));
    if (it == cells_.end()) {
      p.mean[i] = global_;
      continue;
    }
    Eigen::VectorXd t(1);
    t[0] = X(i, 2);
    p.mean[i] = std::max(0.0, fourierReconstruct(t, it->second.rate, it->second.xi, it->second.periods)[0]);
  }
  return p;
}

int FremenBaseline::order(double x1, double x2) const {
  const auto it = cells_.find(key(x1, x2));
  return it == cells_.end() ? -1 : static_cast<int>(it->second.xi.size());
}

void GpHomBaseline::initialize(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& durations,
                               const CopaMapConfig& cfg, const Eigen::MatrixXd* inducing) {
  // Same kernel k_f, initialization and inducing points as CoPA-Map; one latent, Poisson likelihood.
  CopaMap cm = CopaMap::initialize(X, y, durations, cfg, inducing);
  std::vector<LatentGp> lat;
  lat.push_back(cm.model().latents()[0]);
  // log-rate prior mean is 0: start q(u) at log(mean rate) so that exp(f) begins at the data scale.
  lat[0].mu.setConstant(std::log(std::max(1e-3, y.mean())));
  model_ = SvgpModel(std::move(lat), std::make_unique<PoissonLikelihood>(cfg.gh_order), cfg.jitter);
}

TrainReport GpHomBaseline::train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const TrainConfig& cfg) {
  return trainSvgp(model_, X, y, cfg);
}

RatePrediction GpHomBaseline::predict(const Eigen::MatrixXd& X) const {
  RatePrediction p;
  Eigen::VectorXd var;
  model_.predictY(X, p.mean, var);
  p.std = var.cwiseMax(0.0).cwiseSqrt();
  return p;
}

Eigen::VectorXd GpHomBaseline::logPredictiveDensity(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) const {
  return model_.logPredictiveDensity(X, y);
}

}  // namespace cairn::copa_map
