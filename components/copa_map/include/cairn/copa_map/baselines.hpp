// Baselines of the CoPA-Map evaluation (Stüde 2024, §4.3.2): ML (per-cell mean rate), a FreMEn-style
// Poisson/Gamma spectral model (Fr-AAM, Jovan et al. 2016) and GP-Hom (log-Gaussian Cox process: SVGP with a
// Poisson likelihood and exp link, same kernel and initialization as CoPA-Map).
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <map>
#include <utility>
#include <vector>

#include "cairn/copa_map/copa_map.hpp"

namespace cairn::copa_map {

using CellKey = std::pair<long long, long long>;

// ML: the mean of all observed rates of a cell, constant in time; cells never observed get the global mean.
class MlBaseline {
 public:
  explicit MlBaseline(double cell_size = 0.5) : cell_size_(cell_size) {}
  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y);
  RatePrediction predict(const Eigen::MatrixXd& X) const;

 private:
  CellKey key(double x1, double x2) const;
  double cell_size_;
  std::map<CellKey, double> mean_;
  double global_ = 0;
};

struct FremenConfig {
  double cell_size = 0.5;
  double base_period = 0.0;  // candidate periods base/i, i = 1..num_candidates (0: the training time span)
  int num_candidates = 24;
  int max_order = 5;         // components chosen by 5-fold contiguous CV in 0..max_order
  int folds = 5;
  double prior_shape = 1.0;  // Gamma(α, β) prior of the static Poisson rate
  double prior_rate = 1.0;
};

// Per cell: static rate from the Gamma–Poisson posterior (α + Σc)/(β + ΣΔ), plus the b strongest spectral
// components of the residual rates (FreMEn), b chosen by contiguous k-fold CV; predictions clipped at 0.
class FremenBaseline {
 public:
  explicit FremenBaseline(FremenConfig cfg = {}) : cfg_(cfg) {}
  // `durations` in units of the time bin (empty: Δ = 1, i.e. y are counts per bin).
  void fit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& durations);
  RatePrediction predict(const Eigen::MatrixXd& X) const;
  // Number of periodic components chosen for the cell containing (x1, x2) (-1 if unknown).
  int order(double x1, double x2) const;

 private:
  struct Cell {
    double rate = 0;
    std::vector<std::complex<double>> xi;
    std::vector<double> periods;
  };
  CellKey key(double x1, double x2) const;
  FremenConfig cfg_;
  std::map<CellKey, Cell> cells_;
  double global_ = 0;
};

// GP-Hom: one latent f with k_f, y ~ Poisson(exp f); inputs y are used as counts.
class GpHomBaseline {
 public:
  void initialize(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& durations,
                  const CopaMapConfig& cfg, const Eigen::MatrixXd* inducing = nullptr);
  TrainReport train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const TrainConfig& cfg);
  RatePrediction predict(const Eigen::MatrixXd& X) const;
  Eigen::VectorXd logPredictiveDensity(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) const;
  SvgpModel& model() { return model_; }

 private:
  SvgpModel model_;
};

}  // namespace cairn::copa_map
