// Sparse variational GP with one or two latent functions (Stüde 2024, §4.2.3-4.2.5; Saul et al. 2016 chained
// GP; Salimbeni et al. 2018 natural gradients). CoPA-Map uses two latents f, g with the heteroscedastic
// Gaussian likelihood y ~ N(f, softplus(g)) (eq. 4.7); GP-Hom uses one latent with a Poisson likelihood.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cairn/copa_map/kernels.hpp"

namespace cairn::copa_map {

// Marginals q(f_i) = N(m_i, v_i) of one latent over a batch (eqs. 4.13-4.16).
struct LatentMoments {
  Eigen::VectorXd m, v;
};

// Gauss–Hermite nodes and weights for ∫ exp(-x²) h(x) dx (Golub–Welsch).
void gaussHermite(int order, Eigen::VectorXd& nodes, Eigen::VectorXd& weights);

class Likelihood {
 public:
  virtual ~Likelihood() = default;
  virtual std::string type() const = 0;
  virtual int numLatent() const = 0;
  // Σ_i E_q[log p(y_i | latents_i)] and, if grad != nullptr, its derivatives w.r.t. every m_i and v_i.
  virtual double variationalExpectations(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q,
                                         std::vector<LatentMoments>* grad) const = 0;
  // Predictive mean and variance of y (eq. 4.19).
  virtual void predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean, Eigen::VectorXd& var) const = 0;
  // log p(y_i*) = log ∫ p(y*|latents) q(latents) (for NLPD).
  virtual Eigen::VectorXd logPredictiveDensity(const Eigen::VectorXd& y,
                                               const std::vector<LatentMoments>& q) const = 0;
  virtual std::unique_ptr<Likelihood> clone() const = 0;
};

// y ~ N(f, ζ(g)), ζ = softplus (eq. 4.7). The expectation over f is closed form (the integrand is quadratic in
// f, where 2D Gauss–Hermite is exact); the one over g uses Gauss–Hermite quadrature (eqs. 4.12, 4.19).
class HeteroscedasticGaussianLikelihood final : public Likelihood {
 public:
  explicit HeteroscedasticGaussianLikelihood(int gh_order = 20, double min_variance = 1e-6);
  std::string type() const override { return "heteroscedastic_gaussian_softplus"; }
  int numLatent() const override { return 2; }
  double variationalExpectations(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q,
                                 std::vector<LatentMoments>* grad) const override;
  void predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean, Eigen::VectorXd& var) const override;
  Eigen::VectorXd logPredictiveDensity(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q) const override;
  std::unique_ptr<Likelihood> clone() const override {
    return std::make_unique<HeteroscedasticGaussianLikelihood>(*this);
  }
  int ghOrder() const { return static_cast<int>(nodes_.size()); }

 private:
  Eigen::VectorXd nodes_, weights_;
  double min_var_;
};

// y ~ N(f, σ²) with fixed σ² (used to check the SVGP against exact GP regression).
class GaussianLikelihood final : public Likelihood {
 public:
  explicit GaussianLikelihood(double variance) : var_(variance) {}
  std::string type() const override { return "gaussian"; }
  int numLatent() const override { return 1; }
  double variationalExpectations(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q,
                                 std::vector<LatentMoments>* grad) const override;
  void predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean, Eigen::VectorXd& var) const override;
  Eigen::VectorXd logPredictiveDensity(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q) const override;
  std::unique_ptr<Likelihood> clone() const override { return std::make_unique<GaussianLikelihood>(*this); }
  double variance() const { return var_; }

 private:
  double var_;
};

// y ~ Poisson(exp f) (log-Gaussian Cox process, GP-Hom baseline, §4.3.2). Expectations are closed form.
class PoissonLikelihood final : public Likelihood {
 public:
  explicit PoissonLikelihood(int gh_order = 20);
  std::string type() const override { return "poisson_exp"; }
  int numLatent() const override { return 1; }
  double variationalExpectations(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q,
                                 std::vector<LatentMoments>* grad) const override;
  void predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean, Eigen::VectorXd& var) const override;
  Eigen::VectorXd logPredictiveDensity(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q) const override;
  std::unique_ptr<Likelihood> clone() const override { return std::make_unique<PoissonLikelihood>(*this); }

 private:
  Eigen::VectorXd nodes_, weights_;
};

std::unique_ptr<Likelihood> makeLikelihood(const std::string& type, double param);

// One latent GP with inducing inputs Z and q(u) = N(mu, L Lᵀ), L lower triangular (§4.2.5).
struct LatentGp {
  std::unique_ptr<Kernel> kernel;
  Eigen::MatrixXd Z;   // m x 3
  Eigen::VectorXd mu;  // m
  Eigen::MatrixXd L;   // m x m lower triangular
  Eigen::MatrixXd precision;  // cached S⁻¹ (kept by natural-gradient steps; recomputed from L when empty)

  LatentGp() = default;
  LatentGp(std::unique_ptr<Kernel> k, Eigen::MatrixXd z, double init_sqrt_scale = 1.0);
  LatentGp(const LatentGp& o);
  LatentGp& operator=(const LatentGp& o);
  LatentGp(LatentGp&&) = default;
  LatentGp& operator=(LatentGp&&) = default;
};

// Sets q(u) of `lat` from its natural parameters Λ = S⁻¹ (symmetrized) and θ1 = S⁻¹μ; false (and `lat`
// unchanged) when Λ is not positive definite.
bool setNaturalParams(LatentGp& lat, Eigen::MatrixXd Lambda, const Eigen::VectorXd& theta1);

// Result of one ELBO evaluation on a mini-batch, with everything the optimizers need.
struct ElboEvaluation {
  double elbo = 0;  // scale * Σ_batch E[log p] - Σ KL (eq. 4.12)
  double ell = 0;   // unscaled Σ_batch E[log p]
  double kl = 0;
  Eigen::VectorXd hyper_grad;  // ∂elbo/∂(unconstrained kernel parameters of all latents, concatenated)
  std::vector<Eigen::MatrixXd> z_grad;  // ∂elbo/∂Z per latent (m x 3), when requested
  struct PerLatent {
    Eigen::MatrixXd Kinv;  // K_uu⁻¹
    Eigen::VectorXd b;     // Aᵀ ∂E/∂m   (A = K_nu K_uu⁻¹)
    Eigen::MatrixXd Q;     // Aᵀ diag(∂E/∂v) A
    Eigen::VectorXd grad_mu;  // ∂elbo/∂μ
  };
  std::vector<PerLatent> latent;
};

class SvgpModel {
 public:
  SvgpModel() = default;
  SvgpModel(std::vector<LatentGp> latents, std::unique_ptr<Likelihood> lik, double jitter = 1e-5);
  SvgpModel(const SvgpModel& o);
  SvgpModel& operator=(const SvgpModel& o);
  SvgpModel(SvgpModel&&) = default;
  SvgpModel& operator=(SvgpModel&&) = default;

  // ELBO (eq. 4.12) on a batch; `scale` = n / batch size makes it an unbiased estimate of the full bound.
  // `hyper_grad`: gradient w.r.t. the kernel parameters; `z_grad`: w.r.t. the inducing inputs Z (q(u) fixed).
  ElboEvaluation evaluate(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, double scale, bool hyper_grad,
                          bool z_grad = false) const;
  // q(f*) marginals of latent k (eqs. 4.13-4.16), computed in chunks.
  LatentMoments latentMoments(int k, const Eigen::MatrixXd& X) const;
  // Predictive mean and variance of y in model (standardized) units.
  void predictY(const Eigen::MatrixXd& X, Eigen::VectorXd& mean, Eigen::VectorXd& var) const;
  Eigen::VectorXd logPredictiveDensity(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) const;

  // One natural-gradient step of size gamma on q(u_k) (Salimbeni et al. 2018) from an evaluation. Returns the
  // step actually taken (halved until the new precision is positive definite), 0 when no step was possible.
  double naturalGradientStep(int k, const ElboEvaluation& ev, double scale, double gamma);

  Eigen::VectorXd hyperParams() const;
  void setHyperParams(const Eigen::VectorXd& p);
  Eigen::VectorXd hyperLowerBounds() const;
  Eigen::VectorXd hyperUpperBounds() const;
  int numHyperParams() const;

  std::vector<LatentGp>& latents() { return latents_; }
  const std::vector<LatentGp>& latents() const { return latents_; }
  const Likelihood& likelihood() const { return *lik_; }
  double jitter() const { return jitter_; }
  // Mixed precision in evaluate(): A L and Aᵀ diag(∂E/∂v) A (2 B m² of the ≈ 4 B m² flops per latent) in single
  // precision (A = K_nu K_uu⁻¹, the m x m sums and every O(m³) step stay double). Off by default; trainSvgp
  // switches it on for TrainConfig::mixed_precision. Agreement with the double path: test_svgp.cpp.
  void setMixedPrecision(bool on) { mixed_precision_ = on; }
  bool mixedPrecision() const { return mixed_precision_; }

 private:
  struct KuuCache {
    Eigen::VectorXd params;
    Eigen::MatrixXd Z;
    Eigen::MatrixXd Lk;    // Cholesky factor L_K of K_uu + jitter I
    Eigen::MatrixXd Linv;  // L_K⁻¹
    Eigen::MatrixXd Kinv;
  };
  const KuuCache& kuu(int k) const;

  std::vector<LatentGp> latents_;
  std::unique_ptr<Likelihood> lik_;
  double jitter_ = 1e-5;
  bool mixed_precision_ = false;
  // K_uu factorization per latent, reused while the hyperparameters do not change (evaluate() is therefore not
  // thread-safe; prediction does not use the cache).
  mutable std::vector<KuuCache> kuu_cache_;
};

struct TrainConfig {
  int batch_size = 2000;             // mini-batch size (copa-map: 1,100; not given in the thesis)
  int max_iterations = 2000;
  double max_seconds = 600.0;
  double natgrad_gamma_start = 0.1;  // natural-gradient step γ, linear schedule (copa-map: 0.1 -> 0.01)
  double natgrad_gamma_end = 0.1;
  double adam_lr_start = 1e-2;       // Adam on kernel hyperparameters (copa-map: 1e-2 -> 1e-3)
  double adam_lr_end = 1e-3;
  int decay_steps = 100;             // linear decay over the first 100 steps (§4.2.5)
  // What γ and Adam's rate do after the linear warm-up/decay of the first `decay_steps` steps. Stüde §4.2.5
  // gives only the linear decay; with constant steps the stochastic natural-gradient iterates keep jittering
  // around the optimum and the epoch ELBO never settles (stochastic VI needs decaying steps: Hoffman et al.
  // 2013, ρ_t = (t + τ)^(-κ); Robbins–Monro Σγ = ∞, Σγ² < ∞. InvSqrt is κ = ½, the slowest such decay). Constant: γ_end / lr_end from then on. InvSqrt: both multiplied by
  // (1 + (k − decay_steps)/decay_tau)^(-1/2). Plateau: both multiplied by plateau_factor after every epoch whose
  // mean ELBO is below the best epoch mean so far (step decay on a stalled epoch ELBO).
  enum class StepDecay { Constant, InvSqrt, Plateau };
  StepDecay step_decay = StepDecay::Constant;
  double decay_tau = 0;              // InvSqrt time constant in steps; 0 = one epoch (⌈n / batch_size⌉ steps)
  double plateau_factor = 0.5;
  // Polyak–Ruppert (tail) averaging: the returned model is the mean of the iterates after `decay_steps` over the
  // last completed epoch and the current partial one (natural parameters of q(u), unconstrained hyperparameters,
  // Z). The ELBOs in the report are those of the iterates.
  bool average_iterates = false;
  bool train_hyper = true;
  // SvgpModel::setMixedPrecision during training (single-precision A L and Aᵀ diag(∂E/∂v) A products); the
  // model's own setting is restored afterwards. Prediction is always double.
  bool mixed_precision = false;
  // Adam on the inducing inputs Z of every latent (the "and optionally Z"), on the same steps as the
  // hyperparameters; step size in input units (m, time units). Off by default (see the README for ATC).
  bool train_inducing = false;
  double inducing_lr = 0.02;
  int hyper_warmup = 0;              // natural-gradient-only steps before Adam starts
  int hyper_every = 1;               // Adam step on every k-th mini-batch (others: natural gradient only)
  // Convergence (early stopping): the epoch ELBO (one pass over a shuffled partition of the data: every point seen
  // once, Σ E[log p] minus the mean KL, per point) changes by at most
  // tolerance · max(|previous epoch mean ELBO per point|, elbo_floor) per point, in `patience` consecutive
  // epochs. copa-map uses the relative change 1e-3 (elbo_floor = 0). The ELBO per point of standardized outputs
  // is near 0 (it shifts by log of the output scale), where a purely relative test is ill-conditioned; a floor of
  // 1 nat per point makes it an absolute 1e-3 nats per point there.
  double tolerance = 1e-3;
  double elbo_floor = 0.0;
  int patience = 1;
  int min_epochs = 2;
  std::uint64_t seed = 1;
  // Called after every step with (iteration, mini-batch ELBO per point, elapsed seconds).
  std::function<void(int, double, double)> progress;
  // Called after every completed epoch with (epoch count, epoch-mean ELBO per point), the model in its current
  // state (e.g. to score it on held-out data).
  std::function<void(int, double)> on_epoch;
};

// "constant", "invsqrt", "plateau" <-> TrainConfig::StepDecay; an unknown name throws std::invalid_argument.
TrainConfig::StepDecay stepDecayFromName(const std::string& name);
const char* stepDecayName(TrainConfig::StepDecay d);

struct TrainReport {
  int iterations = 0;
  int epochs = 0;
  double seconds = 0;
  double final_elbo = 0;  // ELBO of the last epoch per data point (mean mini-batch ELBO if no epoch completed)
  int averaged_iterates = 0;  // iterates in the returned average (0: the last iterate is returned)
  double final_gamma = 0;  // natural-gradient step γ of the last iteration (after warm-up and decay)
  bool converged = false;
  bool diverged = false;
  std::string message;
  std::vector<double> epoch_elbo;
};

// Alternating natural-gradient (variational parameters) and Adam (hyperparameters) steps on mini-batches
// (§4.2.5). On a non-finite ELBO the last good parameters are restored and training stops with a message.
TrainReport trainSvgp(SvgpModel& model, const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                      const TrainConfig& cfg);

}  // namespace cairn::copa_map
