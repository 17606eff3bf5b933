#include "cairn/graph_slam/optimizer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "block_system.hpp"

namespace cairn::graph_slam {

Algorithm parseAlgorithm(const std::string& name) {
  if (name == "lm") return Algorithm::kLevenbergMarquardt;
  if (name == "gn") return Algorithm::kGaussNewton;
  if (name == "dogleg") return Algorithm::kDogleg;
  throw std::invalid_argument("unknown solver '" + name + "' (expected lm, gn or dogleg)");
}

std::optional<std::size_t> automaticGauge(const PoseGraph& graph) {
  for (const Variable& v : graph.variables()) {
    if (v.fixed) return std::nullopt;
  }
  for (const Factor& f : graph.factors()) {
    if (arity(f.kind) == 1) return std::nullopt;
  }
  const auto& vars = graph.variables();
  for (std::size_t k = 0; k < vars.size(); ++k) {
    if (vars[k].kind == VariableKind::kPose2 || vars[k].kind == VariableKind::kPose3) return k;
  }
  return std::nullopt;
}

struct Optimizer::Impl {
  detail::BlockSystem system;
  std::uint64_t built_version = 0;
  bool built = false;
  std::optional<std::size_t> gauge;
  int symbolic_total = 0;
  int numeric_total = 0;
  double last_lambda = -1.0;
  double last_radius = -1.0;

  bool ensureStructure(const PoseGraph& graph, const OptimizerOptions& o) {
    system.cholesky().setMaxThreads(o.factorization_threads);
    system.cholesky().setReplayDisabled(!o.factorization_replay);
    if (built && built_version == graph.structureVersion()) return false;
    gauge = automaticGauge(graph);
    const int before = system.cholesky().symbolicAnalyses();
    system.build(graph, gauge, static_cast<int>(o.ordering), static_cast<int>(o.factorization),
                 o.nd_min_flops_per_block, o.incremental_ordering, o.incremental_fill_tolerance);
    symbolic_total += system.cholesky().symbolicAnalyses() - before;
    built_version = graph.structureVersion();
    built = true;
    return true;
  }

  bool factorize() {
    ++numeric_total;
    return system.cholesky().factorize();
  }
};

Optimizer::Optimizer(OptimizerOptions options) : options_(options), impl_(std::make_unique<Impl>()) {}
Optimizer::~Optimizer() = default;
Optimizer::Optimizer(Optimizer&&) noexcept = default;
Optimizer& Optimizer::operator=(Optimizer&&) noexcept = default;

namespace {

// Runs f() and adds its wall time to acc.
template <typename F>
auto timed(double& acc, F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  struct Add {
    double& acc;
    std::chrono::steady_clock::time_point t0;
    ~Add() { acc += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); }
  } add{acc, t0};
  return f();
}

double stateNorm(const std::vector<Variable>& values) {
  double s = 0.0;
  for (const Variable& v : values) {
    switch (v.kind) {
      case VariableKind::kPose2: s += v.pose2.t.squaredNorm() + v.pose2.theta * v.pose2.theta; break;
      case VariableKind::kPose3: s += v.pose3.t.squaredNorm() + v.pose3.q.coeffs().squaredNorm(); break;
      case VariableKind::kPoint2:
      case VariableKind::kPoint3: s += v.point.squaredNorm(); break;
    }
  }
  return std::sqrt(s);
}

}  // namespace

OptimizerSummary Optimizer::optimize(PoseGraph& graph) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& im = *impl_;
  OptimizerSummary sum;
  sum.variables = graph.variables().size();
  sum.factors = graph.factors().size();
  sum.structure_rebuilt = timed(sum.time_structure_s, [&] { return im.ensureStructure(graph, options_); });
  if (im.gauge) sum.gauge = graph.variables()[*im.gauge].id;
  sum.ordering_reused = sum.structure_rebuilt && im.system.orderingReused();

  detail::BlockSystem& sys = im.system;
  const int threads = std::max(1, options_.num_threads);
  const int n = sys.size();
  std::vector<Variable> x = graph.variables();
  std::vector<Variable> trial, extended;
  Eigen::VectorXd grad(n), step(n), hdiag(n), dscale(n), tmp(n);

  double chi2 = 0.0;
  // Heading cos/sin of x, of the trial state and of an extended / look-ahead state: evaluate() fills them and
  // the accepted state's are reused by linearize(), so each state's trigonometry is computed once.
  detail::HeadingTrig trig_x, trig_trial, trig_ext;
  detail::computeHeadingTrig(x, trig_x);
  auto linearize = [&] {
    return timed(sum.time_linearize_s, [&] { return sys.linearize(graph, x, grad, threads, &chi2, &trig_x); });
  };
  auto adopt_extended = [&] {
    trial.swap(extended);
    trig_trial.swap(trig_ext);
  };
  auto factorize = [&] { return timed(sum.time_factorize_s, [&] { return im.factorize(); }); };
  auto solve = [&](const Eigen::VectorXd& b, Eigen::VectorXd& out) {
    timed(sum.time_solve_s, [&] { sys.cholesky().solve(b.data(), out.data()); });
  };
  auto multiply = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    timed(sum.time_solve_s, [&] { sys.cholesky().multiply(v.data(), out.data()); });
  };
  double cost = linearize();
  sum.initial_chi2 = chi2;
  sum.initial_cost = cost;
  // An overflowing cost (e.g. values near 1e300) gives no usable step or convergence test: stop, not
  // converged.
  const bool finite_start = std::isfinite(cost);
  if (!finite_start) sum.termination = "initial cost is not finite";
  double* hv = n > 0 ? sys.cholesky().values() : nullptr;
  const std::vector<int>& diag = sys.diagIndex();
  auto save_diag = [&] {
    for (int k = 0; k < n; ++k) hdiag[k] = hv[diag[k]];
    // Marquardt scaling, clamped as in Ceres (1e-6 .. 1e32) so that zero-curvature directions get damped.
    for (int k = 0; k < n; ++k) dscale[k] = std::clamp(hdiag[k], 1e-6, 1e32);
  };
  auto set_damping = [&](double mu) {
    for (int k = 0; k < n; ++k) hv[diag[k]] = hdiag[k] + mu * dscale[k];
  };
  if (n == 0 && finite_start) {
    sum.final_chi2 = chi2;
    sum.final_cost = cost;
    sum.converged = true;
    sum.termination = "no free variables";
  }
  save_diag();

  double lambda = options_.initial_lambda;
  if (options_.warm_start_damping && !sum.structure_rebuilt && im.last_lambda > 0.0) lambda = im.last_lambda;
  double nu = 2.0;
  double radius = options_.initial_radius;
  if (options_.warm_start_damping && !sum.structure_rebuilt && im.last_radius > 0.0) radius = im.last_radius;
  double x_norm = stateNorm(x);
  // Dogleg state: Gauss-Newton step and Cauchy point for the current linearization.
  bool need_solve = true;
  Eigen::VectorXd h_gn(n), h_sd(n), dsq(n), gscaled(n);
  double step_norm_scaled = 0.0;
  // Per linearization (both ends of the dogleg path are fixed, only the radius varies between trial and
  // look-ahead steps): scaled lengths of both ends and the segment d = h_gn - h_sd with c = <D h_sd, D d>,
  // dd = |D d|^2, computed once in dogleg_prepare() instead of at every dogleg step.
  double gn_norm = 0.0, sd_norm = 0.0, seg_c = 0.0, seg_dd = 0.0;
  Eigen::VectorXd seg(n);
  auto dogleg_prepare = [&] {
    gn_norm = h_gn.cwiseProduct(dsq).norm();
    sd_norm = h_sd.cwiseProduct(dsq).norm();
    seg = h_gn - h_sd;
    seg_c = h_sd.cwiseProduct(dsq).dot(seg.cwiseProduct(dsq));
    seg_dd = seg.cwiseProduct(dsq).squaredNorm();
  };
  // Powell's dogleg step for trust-region radius r (scaled norm |D h|) into out; returns its kind.
  auto doglegStep = [&](double r, Eigen::VectorXd& out) -> const char* {
    if (gn_norm <= r) {
      out = h_gn;
      return " gn";
    }
    if (sd_norm >= r || sd_norm == 0.0) {
      if (sd_norm > 0.0) {
        out = h_sd * (r / sd_norm);
      } else {
        out = h_gn * (r / gn_norm);
      }
      return " cauchy";
    }
    // Where the segment Cauchy point -> GN step leaves the (scaled) trust region.
    const double disc = seg_c * seg_c + seg_dd * (r * r - sd_norm * sd_norm);
    const double beta = (-seg_c + std::sqrt(std::max(0.0, disc))) / seg_dd;
    out = h_sd + beta * seg;
    return " dogleg";
  };

  // Factorization reuse ("chord" steps of a modified Newton method): after an accepted step the factor of the
  // previous point's (damped) Hessian still gives a descent direction h = -L^-1 g at the new point. Where
  // Gauss-Newton converges only linearly (large residuals: the neglected second-order term, not the change of
  // J^T Omega J, limits the rate) such a step makes about the progress of a fresh one at a fraction of the
  // cost. The cost comparison is a deterministic flop proxy, so results do not depend on timing:
  // factorization = CHOLMOD's flop count; chord step = two triangular solves (4 nnz(L)), one product with H
  // and linearization + evaluation (~40 d^2 per factor of error dimension d).
  double chord_work = 0.0, full_work = 0.0;
  if (n > 0 && options_.factor_reuse > 0 && options_.algorithm != Algorithm::kGaussNewton) {
    for (const Factor& f : graph.factors()) chord_work += 40.0 * errorDim(f.kind) * errorDim(f.kind);
    chord_work += 4.0 * sys.cholesky().factorNonzeros() + 2.0 * sys.cholesky().colPtr()[n];
    full_work = sys.cholesky().factorFlops() + chord_work;
  }
  const bool reuse_pays = full_work >= options_.factor_reuse_min_gain * chord_work && chord_work > 0.0;
  bool factor_stale = false;  // the factor is from an earlier linearization point and may serve a chord step
  int chord_run = 0;          // consecutive chord steps on the current factor
  double full_decrease = 0.0; // decrease of the last step with a fresh factorization

  while (finite_start && n > 0 && sum.iterations < options_.max_iterations) {
    if (grad.lpNorm<Eigen::Infinity>() <= options_.gradient_tolerance) {
      sum.converged = true;
      sum.termination = "gradient tolerance";
      break;
    }
    double pred = 0.0;
    bool chord = false;
    const char* step_kind = "";
    if (reuse_pays && factor_stale && chord_run < options_.factor_reuse) {
      solve(grad, step);
      step = -step;
      multiply(step, tmp);
      pred = -(2.0 * grad.dot(step) + step.dot(tmp));
      chord = pred > 0.0;
      if (options_.algorithm == Algorithm::kDogleg) {
        // Only inside the trust region; otherwise the regular dogleg step is computed.
        dsq = dscale.cwiseSqrt();
        step_norm_scaled = step.cwiseProduct(dsq).norm();
        chord = chord && step_norm_scaled <= radius;
      }
      if (chord) {
        ++sum.iterations;
      } else {
        factor_stale = false;
      }
    }
    if (chord) {
      // step and pred are set
    } else if (options_.algorithm == Algorithm::kLevenbergMarquardt) {
      set_damping(lambda);
      ++sum.iterations;
      if (!factorize()) {
        // Not positive definite (e.g. an indefinite / singular system): raise the damping, no step.
        lambda *= nu;
        nu *= 2.0;
        if (lambda > 1e32) {
          sum.termination = "damping diverged (system not positive definite)";
          break;
        }
        continue;
      }
      solve(grad, step);
      step = -step;
      // Predicted decrease of F (Madsen/Nielsen): h^T (lambda D h - g).
      pred = step.dot(lambda * dscale.cwiseProduct(step) - grad);
    } else if (options_.algorithm == Algorithm::kGaussNewton) {
      ++sum.iterations;
      double mu = 0.0;
      set_damping(mu);
      bool ok = factorize();
      // A singular / indefinite Gauss-Newton system gets the smallest damping that makes it factorizable.
      for (mu = 1e-12; !ok && mu < 1e32; mu *= 100.0) {
        set_damping(mu);
        ok = factorize();
      }
      if (!ok) {
        sum.termination = "system not positive definite";
        break;
      }
      solve(grad, step);
      step = -step;
      pred = -step.dot(grad);
    } else {
      ++sum.iterations;
      if (need_solve) {
        // The trust region is measured in the scaled norm |D h| with D = sqrt(clamped diag H) (as Ceres does):
        // rotations and translations of very different stiffness then get comparable step lengths.
        dsq = dscale.cwiseSqrt();
        set_damping(0.0);
        gscaled = grad.cwiseQuotient(dscale);  // D^-2 g
        multiply(gscaled, tmp);
        const double vHv = gscaled.dot(tmp);
        // Cauchy point in scaled coordinates: minimizer of the model along -D^-2 g.
        const double alpha = vHv > 0.0 ? grad.dot(gscaled) / vHv : 0.0;
        h_sd = -alpha * gscaled;
        bool ok = factorize();
        bool damped = false;
        for (double mu = 1e-12; !ok && mu < 1e32; mu *= 100.0) {
          set_damping(mu);
          damped = true;
          ok = factorize();
        }
        if (!ok) {
          sum.termination = "system not positive definite";
          break;
        }
        solve(grad, h_gn);
        h_gn = -h_gn;
        if (damped) set_damping(0.0);
        dogleg_prepare();
        need_solve = false;
      }
      step_kind = doglegStep(radius, step);
      step_norm_scaled = step.cwiseProduct(dsq).norm();
      multiply(step, tmp);
      // Predicted decrease of F = sum rho ~ F + 2 g^T h + h^T H h.
      pred = -(2.0 * grad.dot(step) + step.dot(tmp));
    }

    if (!chord && step.norm() <= options_.parameter_tolerance * (x_norm + options_.parameter_tolerance)) {
      sum.converged = true;
      sum.termination = "parameter tolerance";
      break;
    }
    sys.retract(x, step, trial);
    double new_chi2 = 0.0;
    double new_cost = timed(sum.time_evaluate_s, [&] { return sys.evaluate(graph, trial, threads, &new_chi2, trig_trial); });
    if (options_.dogleg_lookahead > 0 && options_.algorithm == Algorithm::kDogleg && !chord &&
        gn_norm > radius && std::isfinite(new_cost) && new_cost < cost) {
      // Trust-region look-ahead: the step was truncated by the region and still lowered the cost. Both ends
      // of the dogleg path are already solved for, so the steps for 2x, 4x, ... the radius (up to the
      // Gauss-Newton step) cost one cost evaluation each (~1 % of a factorization on the 3D sets); the
      // longest that keeps lowering the cost is taken and the radius update sees its length and ratio.
      // (sphere_bignoise otherwise spends 16 iterations at one radius with ratio ~0.57, which neither grows
      // nor shrinks it.)
      double r = radius;
      Eigen::VectorXd cand(n);
      for (int k = 0; k < options_.dogleg_lookahead; ++k) {
        r *= 2.0;
        const char* kind = doglegStep(r, cand);
        sys.retract(x, cand, extended);
        double c_chi2 = 0.0;
        const double c_cost =
            timed(sum.time_evaluate_s, [&] { return sys.evaluate(graph, extended, threads, &c_chi2, trig_ext); });
        if (!(c_cost < new_cost)) break;
        step.swap(cand);
        adopt_extended();
        new_cost = c_cost;
        new_chi2 = c_chi2;
        step_kind = kind;
        if (kind[1] == 'g') break;  // reached the Gauss-Newton step
      }
      if (step_norm_scaled != step.cwiseProduct(dsq).norm()) {
        step_norm_scaled = step.cwiseProduct(dsq).norm();
        multiply(step, tmp);
        pred = -(2.0 * grad.dot(step) + step.dot(tmp));
      }
    }
    const double actual = cost - new_cost;
    const double ratio = pred > 0.0 ? actual / pred : -1.0;
    if (options_.trace) {
      std::fprintf(stderr, "iter %3d cost %.12g trial %.12g ratio %8.3g |step| %9.3g lambda %9.3g radius %9.3g%s\n",
                   sum.iterations, cost, new_cost, ratio, step.norm(), lambda, radius, chord ? " reused" : step_kind);
    }
    bool accept = false;
    if (chord) {
      // A chord step is kept when the model agrees reasonably; otherwise the same point gets a fresh
      // factorization (damping and radius are left alone: the stale factor, not the model, failed).
      accept = std::isfinite(new_cost) && ratio > 0.25;
      if (!accept) {
        factor_stale = false;
        continue;
      }
    } else if (options_.algorithm == Algorithm::kGaussNewton) {
      accept = std::isfinite(new_cost) && new_cost <= cost;
      if (!accept && std::isfinite(new_cost) && new_cost - cost <= options_.function_tolerance * cost) {
        sum.converged = true;  // at the minimum up to rounding
        sum.termination = "function tolerance";
        break;
      }
      if (!accept) {
        sum.termination = "Gauss-Newton step increased the cost";
        break;
      }
    } else if (options_.algorithm == Algorithm::kLevenbergMarquardt) {
      accept = std::isfinite(new_cost) && ratio > 0.0;
      if (accept) {
        // Nielsen's damping update.
        const double r = 2.0 * ratio - 1.0;
        lambda *= std::max(1.0 / 3.0, 1.0 - r * r * r);
        lambda = std::max(lambda, 1e-20);
        nu = 2.0;
      } else {
        lambda *= nu;
        nu *= 2.0;
      }
    } else {
      accept = std::isfinite(new_cost) && ratio > 0.0;
      if (ratio > 0.75) {
        radius = std::max(radius, 3.0 * step_norm_scaled);
      } else if (ratio < 0.25 || !std::isfinite(new_cost)) {
        // Shrink below the step just tried: when that was the (shorter) Gauss-Newton step, halving the radius
        // alone would propose the very same step again.
        radius = 0.5 * std::min(radius, step_norm_scaled);
      }
      if (!accept && radius <= options_.parameter_tolerance * (x_norm + options_.parameter_tolerance)) {
        sum.converged = true;
        sum.termination = "trust region below parameter tolerance";
        break;
      }
    }
    if (!accept) continue;

    double best_cost = new_cost, best_chi2 = new_chi2;
    if (options_.step_extension > 0 && ratio > options_.extension_ratio && std::isfinite(new_cost)) {
      // Step extension, a line search beyond an accepted step. ratio > 1 means the objective fell by more
      // than the quadratic model predicts: along h the model's curvature h^T H h is too large (large-residual
      // graphs, where the Gauss-Newton J^T Omega J exceeds the true Hessian; torus3D and sphere_bignoise sit at
      // ratio ~1.95 for dozens of iterations). Fit phi(a) = cost + d a + c a^2 to the slope d = 2 g^T h at 0
      // and the best phi(a) so far, and try its minimizer (at most 10x further); each try costs one cost
      // evaluation, ~1 % of a factorization on the 3D sets.
      const double d = 2.0 * grad.dot(step);
      double alpha = 1.0;
      for (int k = 0; k < options_.step_extension && d < 0.0; ++k) {
        const double c = (best_cost - cost - d * alpha) / (alpha * alpha);
        const double next = c > 0.0 ? std::min(-d / (2.0 * c), 10.0 * alpha) : 10.0 * alpha;
        if (next < 1.5 * alpha) break;
        sys.retract(x, next * step, extended);
        double ext_chi2 = 0.0;
        const double ext_cost =
            timed(sum.time_evaluate_s, [&] { return sys.evaluate(graph, extended, threads, &ext_chi2, trig_ext); });
        if (!(ext_cost < best_cost)) {
          // Overshot: retry once at the geometric mean of the last good and the failed length.
          if (k + 1 < options_.step_extension && next > 3.0 * alpha) {
            sys.retract(x, std::sqrt(next * alpha) * step, extended);
            const double mid_cost =
                timed(sum.time_evaluate_s, [&] { return sys.evaluate(graph, extended, threads, &ext_chi2, trig_ext); });
            if (mid_cost < best_cost) {
              best_cost = mid_cost;
              best_chi2 = ext_chi2;
              alpha = std::sqrt(next * alpha);
              adopt_extended();
            }
          }
          break;
        }
        best_cost = ext_cost;
        best_chi2 = ext_chi2;
        alpha = next;
        adopt_extended();
      }
      if (options_.trace && alpha > 1.0) {
        std::fprintf(stderr, "          extended x%.3g: cost %.12g\n", alpha, best_cost);
      }
      if (alpha > 1.0) {
        ++sum.extended_steps;
        step_norm_scaled *= alpha;
        if (options_.algorithm == Algorithm::kDogleg) radius = std::max(radius, 3.0 * step_norm_scaled);
      }
    }

    ++sum.accepted_steps;
    x.swap(trial);
    trig_x.swap(trig_trial);
    x_norm = stateNorm(x);
    const double rel = (cost - best_cost) / std::max(cost, std::numeric_limits<double>::min());
    const double decrease = cost - best_cost;
    cost = best_cost;
    chi2 = best_chi2;
    if (chord) {
      ++sum.reused_factorizations;
      ++chord_run;
      // Convergence from a chord step only where its model agreed (0.5 < ratio < 2): then the stale factor is
      // not what made the decrease small. Otherwise keep reusing while a chord step buys at least as much
      // decrease per unit of work as the last fresh step did.
      if (rel < options_.function_tolerance && ratio > 0.5 && ratio < 2.0) {
        sum.converged = true;
        sum.termination = "function tolerance";
        break;
      }
      if (decrease * full_work < full_decrease * chord_work || rel < options_.function_tolerance) {
        factor_stale = false;
      }
      cost = linearize();
      save_diag();
      need_solve = true;
      continue;
    }
    full_decrease = decrease;
    factor_stale = true;
    chord_run = 0;
    if (rel < options_.function_tolerance) {
      sum.converged = true;
      sum.termination = "function tolerance";
      break;
    }
    cost = linearize();
    save_diag();
    need_solve = true;
  }
  if (sum.termination.empty()) sum.termination = "maximum iterations";
  graph.setValues(x);
  sum.final_chi2 = chi2;
  sum.final_cost = cost;
  im.last_lambda = lambda;
  im.last_radius = radius;
  sum.symbolic_analyses = im.symbolic_total;
  sum.numeric_factorizations = im.numeric_total;
  sum.factor_nonzeros = n > 0 ? sys.cholesky().factorNonzeros() : 0.0;
  sum.factor_flops = n > 0 ? sys.cholesky().factorFlops() : 0.0;
  sum.factorization_replayed = n > 0 && options_.factorization_replay && sys.cholesky().replayActive();
  sum.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sum;
}

std::vector<Eigen::MatrixXd> Optimizer::marginalCovariances(const PoseGraph& graph,
                                                            std::span<const VariableId> ids) {
  Impl& im = *impl_;
  im.ensureStructure(graph, options_);
  detail::BlockSystem& sys = im.system;
  const int n = sys.size();
  std::vector<Eigen::MatrixXd> out;
  out.reserve(ids.size());
  Eigen::VectorXd grad(n);
  sys.linearize(graph, graph.variables(), grad, std::max(1, options_.num_threads), nullptr);
  int cols = 0;
  for (VariableId id : ids) {
    const std::size_t v = graph.indexOf(id);
    if (sys.offset(v) >= 0) cols += tangentDim(graph.variables()[v].kind);
  }
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, cols), sol(n, cols);
  if (cols > 0) {
    if (!im.factorize()) throw std::runtime_error("marginal covariances: the Hessian is singular");
    int c = 0;
    for (VariableId id : ids) {
      const std::size_t v = graph.indexOf(id);
      const int o = sys.offset(v);
      if (o < 0) continue;
      for (int k = 0; k < tangentDim(graph.variables()[v].kind); ++k) rhs(o + k, c++) = 1.0;
    }
    // Columns of H^-1 by forward/back substitution with the sparse factor; the dense inverse is never formed.
    sys.cholesky().solve(rhs.data(), sol.data(), cols);
  }
  int c = 0;
  for (VariableId id : ids) {
    const std::size_t v = graph.indexOf(id);
    const int d = tangentDim(graph.variables()[v].kind);
    const int o = sys.offset(v);
    if (o < 0) {
      out.push_back(Eigen::MatrixXd::Zero(d, d));
      continue;
    }
    Eigen::MatrixXd block = sol.block(o, c, d, d);
    out.push_back(0.5 * (block + block.transpose()));
    c += d;
  }
  return out;
}

}  // namespace cairn::graph_slam
