// Initialization of CoPA-Map (Stüde 2024, §4.2.4): periodic hyperparameters of k_t by Algorithm 4.1 (NUDFT,
// contiguous 5-fold CV of top-b reconstructions, weighted k-means of the chosen periods) and inducing inputs by
// Δ-weighted k-means with m = ⌊α_ind n⌋.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <cstdint>
#include <vector>

namespace cairn::copa_map {

// Normalized NUDFT of the mean-free signal (eq. 4.17): ξ_k = (1/J) Σ_j (y_j - ȳ) exp(-i 2π t_j / o_k).
std::vector<std::complex<double>> nudft(const Eigen::VectorXd& t, const Eigen::VectorXd& y,
                                        const std::vector<double>& periods, double mean);

// Reduced Fourier reconstruction (eq. 4.18): ŷ(t) = ȳ + Σ_u 2|ξ_u| cos(2π t / o_u + arg ξ_u). (The thesis
// prints the unnormalized form; with the 1/J-normalized ξ of nudft() the factor 2 gives the amplitude.)
Eigen::VectorXd fourierReconstruct(const Eigen::VectorXd& t, double mean,
                                   const std::vector<std::complex<double>>& xi, const std::vector<double>& periods);

struct PeriodInitConfig {
  int num_series = 10;          // Λ (§4.3)
  int max_periods = 10;         // ψ_max (§4.3)
  double max_variance = 0.95;   // σ²_max (§4.3)
  double cell_size = 5.0;       // spatial cell of the initialization grid [m] (§4.3: 5 m x 5 m x 60 min)
  double time_bin = 1.0;        // temporal bin of the initialization grid, in data time units (60 min)
  double period_min = 2.0;      // candidate periods o: equally spaced in [period_min, period_max]
  double period_max = 0.0;      // 0: half the data's time span
  double period_step = 0.25;
  int folds = 5;
  int min_series_length = 10;   // shorter series are not sampled
  std::uint64_t seed = 1;
};

struct PeriodInitResult {
  std::vector<double> periods;    // γ̂_1..ψ
  std::vector<double> variances;  // σ̂²_1..ψ
  std::vector<int> chosen_b;      // b_l per sampled series
  std::vector<double> all_periods, all_weights;  // o_l, a_l pooled over the series (clustering input)
};

// Algorithm 4.1 on gridded data X = (x1, x2, t) rows, targets y; `counts` (c_i, or y_i Δ_i) weigh the
// roulette-wheel selection of series (empty: y is used). ψ is at least 1.
PeriodInitResult initializePeriods(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                   const Eigen::VectorXd& counts, const PeriodInitConfig& cfg);

struct KMeansResult {
  Eigen::MatrixXd centers;
  std::vector<int> labels;
  double inertia = 0;
};

// Weighted k-means (k-means++ seeding with weights, then Lloyd iterations). Rows of P are points.
KMeansResult weightedKMeans(const Eigen::MatrixXd& P, const Eigen::VectorXd& w, int k, int max_iter,
                            std::uint64_t seed);

// Inducing inputs Z: k-means of X weighted by Δ_i with k = max(1, ⌊α_ind n⌋) (§4.2.4; α_ind = 0.02, §4.3).
Eigen::MatrixXd initializeInducing(const Eigen::MatrixXd& X, const Eigen::VectorXd& durations, double alpha,
                                   int max_iter, std::uint64_t seed);

}  // namespace cairn::copa_map
