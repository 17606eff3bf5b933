#include "cairn/graph_slam/gnc.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace cairn::graph_slam {
namespace {

// 99% quantiles of the chi-square distribution for 1..6 degrees of freedom.
double chi2Quantile99(int dof) {
  static const double q[7] = {0.0, 6.635, 9.210, 11.345, 13.277, 15.086, 16.812};
  return q[std::clamp(dof, 1, 6)];
}

}  // namespace

GncSummary optimizeGnc(PoseGraph& graph, Optimizer& optimizer, const GncOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  GncSummary out;
  const auto& factors = graph.factors();
  const auto& vars = graph.variables();
  std::vector<std::size_t> sel;
  std::vector<double> cbar2;
  for (std::size_t k = 0; k < factors.size(); ++k) {
    const Factor& f = factors[k];
    bool pick = !options.loop_closures_only;
    if (options.loop_closures_only && (f.kind == FactorKind::kBetween2 || f.kind == FactorKind::kBetween3)) {
      pick = std::llabs(vars[f.var[0]].id - vars[f.var[1]].id) != 1;
    }
    if (!pick) continue;
    sel.push_back(k);
    cbar2.push_back(options.inlier_threshold > 0.0 ? options.inlier_threshold : chi2Quantile99(errorDim(f.kind)));
    graph.setFactorWeight(k, 1.0);
  }
  auto residuals = [&] {
    std::vector<double> r2(sel.size());
    for (std::size_t s = 0; s < sel.size(); ++s) {
      const Factor& f = graph.factors()[sel[s]];
      const int d = errorDim(f.kind);
      const Vector6d e = factorError(f, graph.variables());
      r2[s] = e.head(d).dot(f.information.topLeftCorner(d, d) * e.head(d));
    }
    return r2;
  };
  const bool tls = options.surrogate == GncSurrogate::kTruncatedLeastSquares;
  // Non-robust start (GM: mu -> infinity, TLS: mu -> 0; both surrogates are then the quadratic).
  if (options.start_from_least_squares) {
    out.last = optimizer.optimize(graph);
    out.inner_iterations += out.last.iterations;
  }
  std::vector<double> r2 = residuals();
  double r2max_ratio = 0.0;
  for (std::size_t s = 0; s < sel.size(); ++s) r2max_ratio = std::max(r2max_ratio, r2[s] / cbar2[s]);
  // Yang et al. mu_0: GM 2 r_max^2 / c^2; TLS c^2 / (2 r_max^2 - c^2).
  double mu = tls ? 1.0 / std::max(2.0 * r2max_ratio - 1.0, 1e-12) : std::max(1.0, 2.0 * r2max_ratio);
  std::vector<double> w(sel.size(), 1.0);
  int at_end = 0;
  const double final_tolerance = optimizer.options().function_tolerance;
  for (int outer = 0; outer < options.max_outer_iterations && !sel.empty(); ++outer) {
    double change = 0.0;
    for (std::size_t s = 0; s < sel.size(); ++s) {
      double nw;
      if (tls) {
        // GNC-TLS weight (Yang et al. eq. 14): 1 inside mu/(mu+1) c^2, 0 outside (mu+1)/mu c^2, in between
        // c/r sqrt(mu (mu+1)) - mu.
        const double lo = mu / (mu + 1.0) * cbar2[s], hi = (mu + 1.0) / mu * cbar2[s];
        nw = r2[s] <= lo ? 1.0
             : r2[s] >= hi ? 0.0
                           : std::sqrt(cbar2[s] / r2[s]) * std::sqrt(mu * (mu + 1.0)) - mu;
      } else {
        // Closed-form weight update of GNC-GM: w = (mu c^2 / (r^2 + mu c^2))^2.
        const double mc = mu * cbar2[s];
        nw = (mc / (r2[s] + mc)) * (mc / (r2[s] + mc));
      }
      change = std::max(change, std::abs(nw - w[s]));
      w[s] = nw;
      graph.setFactorWeight(sel[s], nw);
    }
    // Intermediate surrogates are solved loosely; the final ones with the optimizer's own tolerance.
    const bool at_target = tls ? false : mu <= 1.0;
    optimizer.options().function_tolerance =
        at_target ? final_tolerance : std::max(final_tolerance, options.inner_function_tolerance);
    out.last = optimizer.optimize(graph);
    out.inner_iterations += out.last.iterations;
    ++out.outer_iterations;
    r2 = residuals();
    if (tls) {
      // Converged once every weight is (numerically) binary and stopped changing.
      bool binary = true;
      for (double x : w) binary = binary && (x < 1e-6 || x > 1.0 - 1e-6);
      if (binary && change < 1e-4) break;
      mu *= options.mu_step;
    } else {
      if (at_target) {
        // At the original Geman-McClure cost: stop once the weights settled (or after a few rounds).
        if (change < 1e-4 || ++at_end >= 5) break;
      }
      mu = std::max(1.0, mu / options.mu_step);
    }
  }
  optimizer.options().function_tolerance = final_tolerance;
  out.weights.assign(factors.size(), 1.0);
  for (std::size_t s = 0; s < sel.size(); ++s) {
    out.weights[sel[s]] = w[s];
    if (w[s] < 0.5) ++out.rejected;
  }
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace cairn::graph_slam
