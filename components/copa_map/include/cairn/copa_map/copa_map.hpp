// CoPA-Map: the full model (Stüde 2024, Ch. 4): initialization (§4.2.4), heteroscedastic SVGP training
// (§4.2.5) and prediction of people rates (eq. 4.19) with expected counts in space-time regions.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <string>

#include "cairn/copa_map/initialization.hpp"
#include "cairn/copa_map/svgp.hpp"

namespace cairn::copa_map {

// Predicted people rate at query points, in data units (counts per observation time unit of the training grid).
struct RatePrediction {
  Eigen::VectorXd mean;  // m_y, negative values clipped at 0 (§4.2.3)
  Eigen::VectorXd std;   // σ_y (empty when a model has no predictive variance)
};

struct CopaMapConfig {
  PeriodInitConfig period_init;      // Algorithm 4.1 (Λ = 10, ψ_max = 10, σ²_max = 0.95; 5 m x 5 m x 60 min)
  double alpha_ind = 0.02;           // α_ind (§4.3)
  int kmeans_iterations = 15;
  double g_inducing_ratio = 0.25;    // q(u_g) uses this fraction of f's inducing points (k-means of Z_f)
  double spatial_lengthscale = 2.0;  // initial l_s1 = l_s2 [m]
  double periodic_lengthscale = 1.0; // initial l_t,i
  double g_variance = 1.0;           // initial σ_g²
  Eigen::Vector3d g_lengthscales{4.0, 4.0, 24.0};  // initial RBF length scales of g (x1 [m], x2 [m], t)
  double jitter = 1e-5;
  int gh_order = 20;                 // Gauss–Hermite points (eq. 4.19)
  double cell_size = 0.5;            // r_s of the training grid [m]
  double time_bin = 1.0;             // τ of the training grid in data time units
  std::uint64_t seed = 1;
};

// Training schedule of the ATC benchmark (docs/benchmarks.md, copa_map): mini-batch 2000, natural-gradient γ
// 0.3 -> 0.1 over the first 100 steps, Adam 1e-2 on every 2nd batch, then γ and Adam's rate halved after every
// epoch whose ELBO is below the best so far (StepDecay::Plateau), seed 1; stops when the epoch ELBO per point
// changes by at most 1e-3 · max(|ELBO per point|, 1) in 2 consecutive epochs, or at 600 s.
TrainConfig atcTrainConfig();

// The reduced configuration used by CI (issue 7): every `stride`-th row of the inducing inputs and exactly
// `batches` mini-batches of atcTrainConfig() (no time limit, no early stop), so that the result depends only on
// the data and the seed, not on the machine's load.
Eigen::MatrixXd everyNthRow(const Eigen::MatrixXd& Z, int stride);
TrainConfig reducedTrainConfig(int batches);

class CopaMap {
 public:
  CopaMap() = default;
  // Algorithm 4.1 + Δ-weighted k-means; `durations` may be empty (all points weighted equally); `inducing` may
  // be given (e.g. the authors' Z) instead of k-means.
  static CopaMap initialize(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& durations,
                            const CopaMapConfig& cfg, const Eigen::MatrixXd* inducing = nullptr,
                            PeriodInitResult* init_out = nullptr);

  TrainReport train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const TrainConfig& cfg);

  RatePrediction predict(const Eigen::MatrixXd& X) const;
  // log p(y_i | x_i) in data units (for NLPD).
  Eigen::VectorXd logPredictiveDensity(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) const;
  // Expected number of people in [x1a, x1b] x [x2a, x2b] over [t0, t1]: (1/(r_s² τ)) ∫ m_y dX' (§4.2.5), by the
  // midpoint rule with `samples_per_cell` points per r_s and per τ.
  double expectedCount(double x1a, double x1b, double x2a, double x2b, double t0, double t1,
                       int samples_per_cell = 1) const;

  SvgpModel& model() { return model_; }
  const SvgpModel& model() const { return model_; }
  double yMean() const { return y_mean_; }
  double yScale() const { return y_scale_; }
  double cellSize() const { return cell_size_; }
  double timeBin() const { return time_bin_; }
  void setStandardization(double mean, double scale) { y_mean_ = mean; y_scale_ = scale; }
  void setGrid(double cell_size, double time_bin) { cell_size_ = cell_size; time_bin_ = time_bin; }
  void setModel(SvgpModel m) { model_ = std::move(m); }

 private:
  SvgpModel model_;
  double y_mean_ = 0.0, y_scale_ = 1.0;  // outputs are standardized (copa-map)
  double cell_size_ = 0.5, time_bin_ = 1.0;
};

}  // namespace cairn::copa_map
