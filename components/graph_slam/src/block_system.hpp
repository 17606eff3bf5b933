// Block-sparse normal equations of a pose graph, assembled directly into a CHOLMOD matrix whose pattern,
// fill-reducing (block AMD) ordering and symbolic factorization are built once per graph structure.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "cairn/graph_slam/pose_graph.hpp"
#include "sparse_cholesky.hpp"

namespace cairn::graph_slam::detail {

struct FactorSlots {
  int off[2] = {-1, -1};       ///< scalar offset of each variable in the (permuted) system, -1 if inactive
  int diag_rel[2] = {0, 0};    ///< position of the diagonal block inside its columns' row lists
  int pair_rel = -1;           ///< position of the off-diagonal upper block inside its columns, -1 if none
  bool first_is_row = true;    ///< the upper off-diagonal block is (var0 rows, var1 cols)
  double cz = 1.0, sz = 0.0;   ///< cos / sin of a Between2 measurement's heading (constant per structure)
};

/// cos / sin of every SE2 variable's heading (zero for other kinds). The optimizer computes it once per state:
/// evaluate() of a trial state fills it and linearize() of the accepted state reuses it (MIT: trigonometry was
/// 16 % of the run time, two sin/cos pairs per factor and evaluation).
using HeadingTrig = std::vector<Eigen::Vector2d>;
void computeHeadingTrig(const std::vector<Variable>& values, HeadingTrig& out);

class BlockSystem {
 public:
  /// Builds pattern, block AMD ordering and symbolic factorization. gauge: a variable index treated as fixed.
  /// ordering: 0 auto (AMD; METIS nested dissection too when the predicted factorization flops exceed
  /// nd_min_flops_per_block per variable block, fewer flops wins), 1 AMD, 2 METIS nested dissection.
  /// reuse_ordering: if the graph only gained variables since the last build, keep the last elimination order
  /// and append the new blocks (no fill-reducing ordering); falls back to a fresh ordering when the factor's
  /// fill per block exceeds the last fresh ordering's by more than reuse_fill_tolerance.
  void build(const PoseGraph& graph, std::optional<std::size_t> gauge, int ordering = 0, int factorization = 0,
             double nd_min_flops_per_block = 5e4, bool reuse_ordering = false, double reuse_fill_tolerance = 0.3);
  /// The last build() kept the previous elimination order.
  bool orderingReused() const { return ordering_reused_; }

  int size() const { return n_; }
  /// Scalar offset of variable v in the system, or -1 if it is fixed / the gauge.
  int offset(std::size_t v) const { return var_offset_[v]; }
  const std::vector<int>& diagIndex() const { return diag_index_; }
  SparseCholesky& cholesky() { return chol_; }

  /// Assembles H = sum w J^T Omega J (into cholesky().values()) and g = sum w J^T Omega e with the IRLS weight
  /// w = weight * rho'(s). Returns the objective sum rho(weight * e^T Omega e); *chi2 gets sum e^T Omega e.
  /// trig: computeHeadingTrig(values), or nullptr to compute it here.
  double linearize(const PoseGraph& graph, const std::vector<Variable>& values, Eigen::VectorXd& grad,
                   int threads, double* chi2, const HeadingTrig* trig = nullptr);
  /// Objective and chi2 only; trig receives computeHeadingTrig(values) for a later linearize().
  double evaluate(const PoseGraph& graph, const std::vector<Variable>& values, int threads, double* chi2,
                  HeadingTrig& trig) const;
  /// out <- values boxplus step for the free variables. Fixed / gauge variables of out are left as they are
  /// when out already has values' size (they must then equal values'), otherwise out is a copy of values first.
  void retract(const std::vector<Variable>& values, const Eigen::VectorXd& step, std::vector<Variable>& out) const;

 private:
  int n_ = 0;
  std::vector<int> var_offset_;
  std::vector<FactorSlots> slots_;
  std::vector<int> diag_index_;
  std::vector<std::vector<double>> thread_h_;
  std::vector<Eigen::VectorXd> thread_g_;
  HeadingTrig trig_scratch_;
  SparseCholesky chol_;
  // Incremental ordering state: ids and active flags of the variables at the last build, the elimination
  // order as variable indices, and the fill per block of the last fresh ordering.
  std::vector<VariableId> prev_ids_;
  std::vector<char> prev_active_;
  std::vector<std::size_t> order_vars_;
  double full_fill_per_block_ = 0.0;
  bool ordering_reused_ = false;
};

}  // namespace cairn::graph_slam::detail
