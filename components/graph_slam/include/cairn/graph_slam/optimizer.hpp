// Nonlinear least-squares optimizer for PoseGraph (Stüde eq. 3.5: x* = argmin sum rho(e^T Omega e)):
// Gauss-Newton, Levenberg-Marquardt (Nielsen damping update, step rejection) and Powell's dogleg on a
// block-sparse Hessian factorized with CHOLMOD. The pattern, block AMD ordering and symbolic factorization are
// cached per graph structure (PoseGraph::structureVersion()), so re-optimizing after value changes or
// warm-starting only refactorizes numerically.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/pose_graph.hpp"

namespace cairn::graph_slam {

enum class Algorithm { kLevenbergMarquardt, kGaussNewton, kDogleg };

/// Fill-reducing ordering of the variable blocks. kAuto (default): AMD, and where the predicted factorization
/// cost per variable block exceeds OptimizerOptions::nd_min_flops_per_block also METIS nested dissection,
/// keeping the one with fewer predicted flops (3D tori/spheres: -27..-34 % flops; 2D benchmark graphs stay
/// on AMD, where METIS's ordering time exceeds its gain).
enum class Ordering { kAuto, kAmd, kNestedDissection };

/// CHOLMOD factorization kind; kAuto lets CHOLMOD choose from the flop count per factor nonzero.
enum class Factorization { kAuto, kSimplicial, kSupernodal };

/// Parses "lm", "gn", "dogleg"; throws std::invalid_argument.
Algorithm parseAlgorithm(const std::string& name);

struct OptimizerOptions {
  Algorithm algorithm = Algorithm::kDogleg;
  int max_iterations = 100;
  /// Stop when an accepted step lowers the objective by less than this fraction.
  double function_tolerance = 1e-10;
  /// Stop when max |gradient| falls below this.
  double gradient_tolerance = 1e-12;
  /// Stop when |step| <= parameter_tolerance * (|x| + parameter_tolerance).
  double parameter_tolerance = 1e-10;
  /// LM: initial damping lambda; the damping matrix is lambda * diag(H) (Marquardt scaling, clamped).
  double initial_lambda = 1e-4;
  /// Dogleg: initial trust-region radius.
  double initial_radius = 1e4;
  Ordering ordering = Ordering::kAuto;
  /// kAuto: try nested dissection when the AMD factorization is predicted to cost more than this many flops
  /// per variable block.
  double nd_min_flops_per_block = 5e4;
  Factorization factorization = Factorization::kAuto;
  /// Threads for linearization / cost evaluation (>= 1).
  int num_threads = 2;
  /// Cap on the OpenMP threads CHOLMOD's supernodal factorization may use (>= 1). CHOLMOD 3 asks for 4; on the
  /// 2-core benchmark machine 1 was 1.8-2x faster (README "Linear algebra").
  int factorization_threads = 1;
  /// Reuse the last LM damping / dogleg radius when optimizing the same structure again (incremental use).
  bool warm_start_damping = false;
  /// Step extension: after an accepted step whose actual decrease exceeds extension_ratio x the predicted
  /// one, up to this many cost evaluations try longer steps along the same direction (quadratic line-search
  /// fit); 0 disables.
  int step_extension = 3;
  double extension_ratio = 1.2;
  /// Dogleg: when a step truncated by the trust region lowered the cost, up to this many cost evaluations try
  /// the dogleg steps for 2x, 4x, ... the radius (until the Gauss-Newton step) and keep the best; 0 disables.
  int dogleg_lookahead = 4;
  /// LM / dogleg: up to this many consecutive steps may reuse the previous point's factorization
  /// (h = -L^-1 g, kept when actual/predicted decrease > 0.25 and it pays per unit of work); 0 disables.
  int factor_reuse = 8;
  /// Reuse only where a fresh step costs at least this many times a reused one (flop proxy: CHOLMOD's
  /// factorization flops vs solves + linearization); skips small graphs where factorizing is cheap.
  double factor_reuse_min_gain = 4.0;
  /// Incremental use: when the graph only gained variables / factors since the last optimize() (same ids in
  /// the same order, no variable re-fixed), keep the previous elimination order and append the new variables
  /// instead of re-running the fill-reducing ordering; a fresh ordering is computed when the factor's fill per
  /// variable grows beyond incremental_fill_tolerance over the last fresh ordering's. Off by default: on the
  /// M3500 replay (`cairn-slam-bench --incremental`) it cut the structure time by a third but the extra fill
  /// made the factorizations cost more than that (README "Incremental use").
  bool incremental_ordering = false;
  double incremental_fill_tolerance = 0.3;
  /// Where CHOLMOD picks a simplicial LDL^T factor (small, very sparse systems: MIT, Intel, M3500), replay its
  /// numeric factorization on row patterns recorded once per symbolic analysis instead of letting CHOLMOD
  /// recompute them (its up-looking method walks the elimination tree for every row at every call). The same
  /// floating-point operations in the same order, so results are bit-identical (checked against CHOLMOD's
  /// factor when recording; a mismatch falls back to CHOLMOD). MIT: factorization phase about -60 %.
  bool factorization_replay = true;
  /// Print one line per iteration (cost, step, damping / radius) to stderr.
  bool trace = false;
};

struct OptimizerSummary {
  std::size_t variables = 0;
  std::size_t factors = 0;
  double initial_chi2 = 0.0;  ///< sum e^T Omega e before (Stüde eq. 3.4)
  double final_chi2 = 0.0;
  double initial_cost = 0.0;  ///< sum rho(weight * e^T Omega e) before (equals chi2 without kernels)
  double final_cost = 0.0;
  int iterations = 0;         ///< linear solves (accepted and rejected steps)
  int accepted_steps = 0;
  int extended_steps = 0;     ///< accepted steps lengthened by the step extension
  int reused_factorizations = 0;  ///< accepted steps solved with the previous point's factorization
  bool converged = false;
  std::string termination;
  double time_s = 0.0;
  /// Wall time per phase (profile): pattern + ordering + symbolic analysis, linearization + assembly,
  /// numeric factorization, triangular solves / products, cost evaluation of trial steps.
  double time_structure_s = 0.0;
  double time_linearize_s = 0.0;
  double time_factorize_s = 0.0;
  double time_solve_s = 0.0;
  double time_evaluate_s = 0.0;
  bool structure_rebuilt = false;      ///< this call rebuilt pattern + symbolic analysis
  bool ordering_reused = false;        ///< ... keeping the previous elimination order (incremental_ordering)
  int symbolic_analyses = 0;           ///< cumulative over the optimizer's life
  int numeric_factorizations = 0;      ///< cumulative over the optimizer's life
  double factor_nonzeros = 0.0;        ///< nonzeros of the Cholesky factor (fill-in diagnostic)
  double factor_flops = 0.0;           ///< floating-point operations of one numeric factorization
  bool factorization_replayed = false; ///< numeric factorizations were replayed (factorization_replay)
  std::optional<VariableId> gauge;     ///< variable held fixed automatically (nothing fixed, no priors)
};

class Optimizer {
 public:
  explicit Optimizer(OptimizerOptions options = {});
  ~Optimizer();
  Optimizer(Optimizer&&) noexcept;
  Optimizer& operator=(Optimizer&&) noexcept;

  const OptimizerOptions& options() const { return options_; }
  OptimizerOptions& options() { return options_; }

  /// Optimizes the graph's values in place, starting from the current values.
  OptimizerSummary optimize(PoseGraph& graph);

  /// Marginal covariances (in the tangent space of geometry.hpp's retract) of the given variables at the
  /// current values, from the sparse Cholesky factor of the Hessian (for uncertainty metrics such as Yuan's
  /// √det Σ; the SLAM's loop-search radius, Stüde eq. 3.8, uses the compounded odometry covariance instead). Fixed / gauge variables get zero matrices. Throws std::runtime_error if the
  /// Hessian is singular.
  std::vector<Eigen::MatrixXd> marginalCovariances(const PoseGraph& graph, std::span<const VariableId> ids);

 private:
  struct Impl;
  OptimizerOptions options_;
  std::unique_ptr<Impl> impl_;
};

/// The variable the optimizer holds fixed to remove the gauge freedom: the first pose, when no variable is
/// fixed and no prior factor exists; otherwise none.
std::optional<std::size_t> automaticGauge(const PoseGraph& graph);

}  // namespace cairn::graph_slam
