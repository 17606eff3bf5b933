// Thin RAII wrapper around CHOLMOD (private to the core; CHOLMOD headers never reach public headers).
#pragma once

#include <cholmod.h>

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace cairn::graph_slam::detail {

/// Owns a cholmod_common, one symmetric (upper-stored) matrix and its factor. The symbolic analysis is done
/// once by analyze(); factorize() is numeric only and may be called any number of times after the values
/// of matrix() changed (same pattern).
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Allocates an n x n upper-stored matrix with the given CSC pattern (values zero); drops any factor.
  void setPattern(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx);
  cholmod_sparse* matrix() { return a_; }
  double* values() { return static_cast<double*>(a_->x); }
  const int* colPtr() const { return static_cast<const int*>(a_->p); }
  int size() const { return a_ != nullptr ? static_cast<int>(a_->nrow) : 0; }

  /// Symbolic analysis. natural_ordering: the pattern is already in a fill-reducing order (the optimizer
  /// orders the blocks with AMD itself); otherwise CHOLMOD's default orderings are tried.
  /// kind: 0 auto, 1 simplicial, 2 supernodal.
  void analyze(bool natural_ordering, int kind = 0);
  bool analyzed() const { return l_ != nullptr; }
  /// Numeric factorization; false if the matrix is not positive definite. For a simplicial LDL^T factor
  /// (CHOLMOD's choice on small, very sparse systems such as MIT's) the first successful factorization after
  /// analyze() records CHOLMOD's row patterns (the elimination-tree walks its up-looking factorization repeats
  /// for every row at every call); later calls replay exactly the same floating-point operations in the same
  /// order on the recorded patterns, so the factor is bit-identical to CHOLMOD's (checked against CHOLMOD's own
  /// result when the patterns are recorded; any mismatch disables the replay for this analysis).
  bool factorize();
  /// The replay described at factorize() is active (diagnostic / tests).
  bool replayActive() const { return replay_ready_; }
  /// Turns the replay off (true) or back on (false, the default).
  void setReplayDisabled(bool disabled) { replay_off_ = disabled; }
  /// Upper bound on the OpenMP threads CHOLMOD's supernodal kernels may use (>= 1). CHOLMOD 3 hard-codes
  /// num_threads(4) in its assembly loops; the cap is applied around each call through the OpenMP runtime's
  /// dynamic adjustment (no effect when CHOLMOD was built without OpenMP).
  void setMaxThreads(int threads) { max_threads_ = threads < 1 ? 1 : threads; }
  /// Solves A X = B for ncols right-hand sides stored column-major (n x ncols).
  void solve(const double* b, double* x, int ncols = 1);
  /// y = A x (A symmetric, upper stored).
  void multiply(const double* x, double* y);

  int symbolicAnalyses() const { return symbolic_analyses_; }
  int numericFactorizations() const { return numeric_factorizations_; }
  /// Nonzeros of the factor (after analyze()).
  double factorNonzeros() const;
  /// Floating-point operations of one numeric factorization (after analyze()).
  double factorFlops() const { return common_.fl; }
  cholmod_common* common() { return &common_; }

 private:
  void freeWork();
  bool recordReplay();
  bool replayFactorize();
  cholmod_common common_;
  cholmod_sparse* a_ = nullptr;
  cholmod_factor* l_ = nullptr;
  cholmod_dense* x_ = nullptr;
  cholmod_dense* y_ = nullptr;
  cholmod_dense* e_ = nullptr;
  int max_threads_ = 1;
  // Replay of CHOLMOD's simplicial LDL^T factorization: for row k, the columns i of L with L(k,i) != 0 in the
  // order CHOLMOD processes them (replay_i_[replay_ptr_[k] .. replay_ptr_[k+1])) and the position of L(k,i)
  // in L->x (replay_pos_).
  bool replay_ready_ = false;
  bool replay_failed_ = false;
  bool replay_off_ = false;
  std::vector<int> replay_ptr_, replay_i_, replay_pos_;
  std::vector<double> replay_work_;
  int symbolic_analyses_ = 0;
  int numeric_factorizations_ = 0;
};

/// Fill-reducing ordering of a symmetric pattern (CSC, both triangles or one, diagonal optional):
/// method 0 = try AMD and METIS nested dissection and keep the one CHOLMOD predicts less fill / fewer flops
/// for, 1 = AMD only, 2 = METIS only. Returns perm (new position k holds old index perm[k]); *flops (if
/// given) gets CHOLMOD's predicted factorization flop count of the pattern under that ordering.
std::vector<int> fillReducingOrdering(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx,
                                      int method, double* flops = nullptr);

/// Solves the SPD system A X = B given the upper triangle of A as triplets (duplicates summed).
/// Throws std::runtime_error if A is not positive definite.
Eigen::MatrixXd solveSparseSpd(int n, const std::vector<Eigen::Triplet<double>>& upper, const Eigen::MatrixXd& b);

}  // namespace cairn::graph_slam::detail
