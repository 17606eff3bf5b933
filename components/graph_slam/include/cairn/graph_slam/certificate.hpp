// Global-optimality certificate of SE-Sync (Rosen, Carlone, Bandeira, Leonard, IJRR 2019) for SE(2)/SE(3)
// pose graphs made of relative-pose factors.
//
// SE-Sync's maximum-likelihood problem (its Problem 1) with isotropic weights:
//   f(t, R) = sum_ij kappa_ij |R_j - R_i Rz_ij|_F^2 + tau_ij |t_j - t_i - R_i tz_ij|^2,
// kappa, tau derived from each edge's information matrix as SE-Sync's g2o reader does (seSyncWeights()).
// With Y = [t_1 .. t_n | R_1 .. R_n] (d x (n + d n)), f(Y) = tr(Y M Y^T) for a sparse PSD data matrix M
// (translation-explicit form: SE-Sync eliminates t to get its Q = Schur complement of M; keeping t makes the
// certificate matrix sparse, and S ⪰ 0 here <=> Q - Lambda ⪰ 0 there, because the Lagrange multipliers vanish
// on the translation block and M_tt is a connected graph's Laplacian).
//
// certifyGlobalOptimum() (a) refines the given values to a first-order critical point of f (Riemannian
// Levenberg-Marquardt, rotations on SO(d)), (b) forms the multipliers Lambda_i = Sym(R_i^T (Y M)_{R_i}) of the
// orthogonality constraints and S = M - blockdiag(0, Lambda_1 .. Lambda_n), and (c) decides S ⪰ 0 by a
// CHOLMOD Cholesky factorization of S + eta I (succeeds <=> lambda_min(S) > -eta). If S ⪰ 0, every feasible
// Y' satisfies f(Y') = tr(Y' S Y'^T) + sum tr(Lambda_i) >= sum tr(Lambda_i) = f(Y): the refined point is a
// global minimizer (even of the O(d) relaxation). S always has the rows of Y and the all-ones translation
// vector (the gauge) in its null space at a critical point, so lambda_min(S) = 0 there is the certified case.
#pragma once

#include <cstddef>
#include <optional>

#include "cairn/graph_slam/pose_graph.hpp"

namespace cairn::graph_slam {

/// SE-Sync's isotropic weights of one relative-pose factor (SE-Sync's g2o reader): 2D tau = 2 / tr(Omega_t^-1),
/// kappa = Omega_thth; 3D tau = 3 / tr(Omega_t^-1), kappa = 3 / (2 tr(Omega_r^-1)).
struct SeSyncWeights {
  double kappa = 0.0;
  double tau = 0.0;
};
SeSyncWeights seSyncWeights(const Factor& f);

/// SE-Sync's objective f at the graph's current values. Throws std::invalid_argument if the graph has factors
/// other than Between2 / Between3 or variables other than poses of one dimension.
double seSyncObjective(const PoseGraph& graph);

struct CertificateOptions {
  /// Riemannian LM on f: at most this many linear solves (MIT from cairn's stored-guess solution needs ~410).
  int max_iterations = 1000;
  /// Stop when an accepted step lowers f by less than this fraction of f (or of the scale when f ~ 0).
  double function_tolerance = 1e-14;
  /// Stop when |grad f| (Euclidean norm over all poses' tangent coordinates) falls below this times the
  /// gradient scale sqrt(sum of the weights) (f is a sum of weighted squared residuals).
  double gradient_tolerance = 1e-12;
  /// eta = eta_relative * max_i S_ii: the certificate accepts lambda_min(S) > -eta. Our choice (README
  /// "Global optimality"): certified benchmark points have lambda_min ~ 1e-16 relative (the known null space),
  /// while the smallest genuine eigenvalue seen (MIT) is 1e-8 relative, so the tolerance stays well below it.
  double eta_relative = 1e-10;
  /// When not certified: bisect the shift of S + sigma I (Cholesky succeeds <=> sigma > -lambda_min) until the
  /// bracket of lambda_min is this tight (relative).
  double lambda_relative_precision = 1e-3;
  /// Skip step (a): certify the values as given (they must be a critical point already).
  bool refine = true;
};

struct CertificateResult {
  bool certified = false;       ///< lambda_min(S) > -eta
  int dimension = 0;            ///< d (2 or 3)
  std::size_t poses = 0;
  std::size_t edges = 0;
  double objective_input = 0.0; ///< f at the given values
  double objective = 0.0;       ///< f at the refined critical point (= f* when certified)
  /// sum_i tr(Lambda_i) = f(Y) - tr(Y S Y^T). If lambda_min(S) >= 0, every feasible Y' has f(Y') >= this, so it
  /// is a lower bound on f* even where the refinement stopped short of a critical point: f* lies in
  /// [dual_bound, objective]. The Cholesky tests only show lambda_min >= lambda_min_lower, which weakens it to
  /// f* >= dual_bound - |lambda_min_lower| |Y*|_F^2 (Y* the optimum with centered translations);
  /// dual_bound_slack is that term evaluated with this Y's scale (an estimate, not a bound).
  double dual_bound = 0.0;
  double dual_bound_slack = 0.0;
  int refine_iterations = 0;    ///< LM linear solves
  /// The LM stopped on its function / gradient tolerance (a critical point), not on max_iterations. The
  /// certificate's "no" means "not the global optimum" only at a critical point.
  bool refine_converged = false;
  double gradient_norm = 0.0;   ///< |grad f| at the refined point (all poses, tangent coordinates)
  /// |Y S|_F / |Y M|_F at the refined point: how exactly the multipliers satisfy stationarity.
  double stationarity = 0.0;
  double eta = 0.0;             ///< absolute tolerance used
  /// Certified: lambda_min(S) lies in [lambda_min_lower, lambda_min_upper], lower = -(smallest shift eta / 10^k
  /// >= 1e-14 max S_ii for which S + shift I still factorizes), upper = Rayleigh quotient on the known null space;
  /// not certified: lambda_min(S) lies in
  /// [lambda_min_lower, lambda_min_upper] (bisection bracket, both negative) and lambda_min = their midpoint.
  double lambda_min = 0.0;
  double lambda_min_lower = 0.0;
  double lambda_min_upper = 0.0;
  /// Smallest eigenvalue of S on the complement of its known null space (rows of Y, the translation gauge),
  /// estimated by deflated inverse iteration (Rayleigh quotient, an upper bound); certified only. > 0 means
  /// the certificate holds with margin.
  double lambda_deflated = 0.0;
  int factorizations = 0;       ///< Cholesky factorizations of S + sigma I
  double time_s = 0.0;
};

/// Runs (a)-(c) above on the graph's pose values; refined (if given) receives the graph with the refined
/// critical point as values. Fixed flags are ignored (f is gauge invariant; SE-Sync fixes nothing). Throws
/// std::invalid_argument for graphs with priors, points or mixed dimensions, or an empty graph.
CertificateResult certifyGlobalOptimum(const PoseGraph& graph, const CertificateOptions& options = {},
                                       PoseGraph* refined = nullptr);

}  // namespace cairn::graph_slam
