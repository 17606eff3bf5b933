#include "sparse_cholesky.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#ifdef CAIRN_HAVE_OPENMP_RUNTIME
#include <omp.h>
#endif

namespace cairn::graph_slam::detail {
namespace {

// Caps the threads of CHOLMOD's OpenMP regions for the lifetime of the guard. The regions request a fixed
// num_threads(4); with dynamic adjustment on, the runtime may give fewer, and libgomp gives at most
// omp_get_max_threads(). Measured on the 2-core benchmark VM (torus3D, 10 iterations): 4 threads cost 1.8-2x
// the wall time of 1 (fork/join and futex wake-ups around small supernodes on an oversubscribed machine).
class OmpThreadCap {
 public:
  explicit OmpThreadCap([[maybe_unused]] int threads) {
#ifdef CAIRN_HAVE_OPENMP_RUNTIME
    dynamic_ = omp_get_dynamic();
    max_ = omp_get_max_threads();
    omp_set_dynamic(1);
    omp_set_num_threads(threads);
#endif
  }
  ~OmpThreadCap() {
#ifdef CAIRN_HAVE_OPENMP_RUNTIME
    omp_set_dynamic(dynamic_);
    omp_set_num_threads(max_);
#endif
  }
  OmpThreadCap(const OmpThreadCap&) = delete;
  OmpThreadCap& operator=(const OmpThreadCap&) = delete;

 private:
  [[maybe_unused]] int dynamic_ = 0;
  [[maybe_unused]] int max_ = 1;
};

}  // namespace

SparseCholesky::SparseCholesky() {
  cholmod_start(&common_);
  common_.quick_return_if_not_posdef = 1;
  common_.print = 0;
}

SparseCholesky::~SparseCholesky() {
  freeWork();
  if (l_ != nullptr) cholmod_free_factor(&l_, &common_);
  if (a_ != nullptr) cholmod_free_sparse(&a_, &common_);
  cholmod_finish(&common_);
}

void SparseCholesky::freeWork() {
  if (x_ != nullptr) cholmod_free_dense(&x_, &common_);
  if (y_ != nullptr) cholmod_free_dense(&y_, &common_);
  if (e_ != nullptr) cholmod_free_dense(&e_, &common_);
}

void SparseCholesky::setPattern(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx) {
  freeWork();
  replay_ready_ = false;
  replay_failed_ = false;
  if (l_ != nullptr) cholmod_free_factor(&l_, &common_);
  if (a_ != nullptr) cholmod_free_sparse(&a_, &common_);
  a_ = cholmod_allocate_sparse(n, n, row_idx.size(), /*sorted=*/1, /*packed=*/1, /*stype=*/1, CHOLMOD_REAL,
                               &common_);
  if (a_ == nullptr) throw std::runtime_error("CHOLMOD: cannot allocate the Hessian");
  std::copy(col_ptr.begin(), col_ptr.end(), static_cast<int*>(a_->p));
  std::copy(row_idx.begin(), row_idx.end(), static_cast<int*>(a_->i));
  std::fill_n(static_cast<double*>(a_->x), row_idx.size(), 0.0);
}

void SparseCholesky::analyze(bool natural_ordering, int kind) {
  if (l_ != nullptr) cholmod_free_factor(&l_, &common_);
  common_.supernodal = kind == 1 ? CHOLMOD_SIMPLICIAL : kind == 2 ? CHOLMOD_SUPERNODAL : CHOLMOD_AUTO;
  if (natural_ordering) {
    common_.nmethods = 1;
    common_.method[0].ordering = CHOLMOD_NATURAL;
    // No postordering: an identity permutation lets cholmod_factorize use the matrix as stored instead of
    // transposing a permuted copy at every numeric factorization (the block ordering is already postordered).
    common_.postorder = 0;
  } else {
    common_.nmethods = 0;
    common_.postorder = 1;
  }
  l_ = cholmod_analyze(a_, &common_);
  if (l_ == nullptr) throw std::runtime_error("CHOLMOD: symbolic analysis failed");
  ++symbolic_analyses_;
  replay_ready_ = false;
  replay_failed_ = false;
}

bool SparseCholesky::factorize() {
  ++numeric_factorizations_;
  if (replay_ready_ && !replay_off_) return replayFactorize();
  const OmpThreadCap cap(max_threads_);
  const int ok = cholmod_factorize(a_, l_, &common_);
  const bool success = ok != 0 && common_.status == CHOLMOD_OK && l_->minor == l_->n;
  if (success && !replay_ready_ && !replay_failed_ && !replay_off_) {
    replay_ready_ = recordReplay();
    replay_failed_ = !replay_ready_;
  }
  return success;
}

// Records the row patterns of CHOLMOD's up-looking simplicial LDL^T factorization (cholmod_rowfac) of the
// upper-stored matrix in natural order: row k of L is reached from the entries of column k of A by walking the
// elimination tree up to k, each walk's path pushed onto a stack, and the stack processed top down. Then
// replays the factorization once on the current matrix and compares it bit for bit with CHOLMOD's factor.
bool SparseCholesky::recordReplay() {
  if (l_->is_super || l_->is_ll || l_->xtype != CHOLMOD_REAL || a_->stype <= 0 || !a_->packed || !a_->sorted ||
      l_->ordering != CHOLMOD_NATURAL) {
    return false;
  }
  const int n = static_cast<int>(l_->n);
  const int* ap = static_cast<const int*>(a_->p);
  const int* ai = static_cast<const int*>(a_->i);
  const int* lp = static_cast<const int*>(l_->p);
  const int* li = static_cast<const int*>(l_->i);
  const int* lnz = static_cast<const int*>(l_->nz);
  std::vector<int> parent(n), flag(n, -1), stack(n), count(n, 1);
  for (int j = 0; j < n; ++j) parent[j] = lnz[j] > 1 ? li[lp[j] + 1] : -1;
  replay_ptr_.assign(1, 0);
  replay_i_.clear();
  replay_pos_.clear();
  for (int k = 0; k < n; ++k) {
    int top = n;
    flag[k] = k;
    for (int p = ap[k]; p < ap[k + 1]; ++p) {
      int len = 0;
      for (int i = ai[p]; i < k && i >= 0 && flag[i] != k; i = parent[i]) {
        stack[len++] = i;
        flag[i] = k;
      }
      while (len > 0) stack[--top] = stack[--len];
    }
    for (; top < n; ++top) {
      const int i = stack[top];
      const int pos = lp[i] + count[i]++;
      if (count[i] > lnz[i] || li[pos] != k) return false;  // not CHOLMOD's pattern
      replay_i_.push_back(i);
      replay_pos_.push_back(pos);
    }
    replay_ptr_.push_back(static_cast<int>(replay_i_.size()));
  }
  for (int j = 0; j < n; ++j) {
    if (count[j] != lnz[j]) return false;
  }
  // Self-check: the replay must reproduce CHOLMOD's factor exactly.
  double* lx = static_cast<double*>(l_->x);
  std::vector<double> reference(lx, lx + lp[n]);
  replay_work_.assign(n, 0.0);
  const bool ok = replayFactorize();
  bool same = ok;
  for (int j = 0; same && j < n; ++j) {
    same = std::memcmp(lx + lp[j], reference.data() + lp[j], sizeof(double) * lnz[j]) == 0;
  }
  if (!same) std::copy(reference.begin(), reference.end(), lx);
  l_->minor = l_->n;
  return same;
}

// The numeric part of cholmod_rowfac's real LDL^T case on the recorded patterns: for each row k, scatter column
// k of A into W; for each i of the row pattern in order: y = W(i), W(rows of L(:,i) above k) -= L(.,i) y,
// L(k,i) = y / D(i), D(k) -= L(k,i) y. A pivot D(k) that is not positive and finite fails, as for LL^T.
bool SparseCholesky::replayFactorize() {
  const int n = static_cast<int>(l_->n);
  const int* ap = static_cast<const int*>(a_->p);
  const int* ai = static_cast<const int*>(a_->i);
  const double* ax = static_cast<const double*>(a_->x);
  const int* lp = static_cast<const int*>(l_->p);
  const int* li = static_cast<const int*>(l_->i);
  double* lx = static_cast<double*>(l_->x);
  double* w = replay_work_.data();
  const int* ri = replay_i_.data();
  const int* rpos = replay_pos_.data();
  for (int k = 0; k < n; ++k) {
    for (int p = ap[k]; p < ap[k + 1]; ++p) {
      if (ai[p] <= k) w[ai[p]] = ax[p];
    }
    double dk = w[k];
    w[k] = 0.0;
    for (int t = replay_ptr_[k]; t < replay_ptr_[k + 1]; ++t) {
      const int i = ri[t];
      const int pos = rpos[t];
      const double yi = w[i];
      w[i] = 0.0;
      const int p0 = lp[i];
      for (int q = p0 + 1; q < pos; ++q) w[li[q]] -= lx[q] * yi;
      const double lki = yi / lx[p0];
      dk -= lki * yi;
      lx[pos] = lki;
    }
    if (!(dk > 0.0) || !std::isfinite(dk)) {
      // Leave W clean for the next call; the factor is invalid (as after a failed CHOLMOD factorization).
      std::fill(replay_work_.begin(), replay_work_.end(), 0.0);
      l_->minor = static_cast<size_t>(k);
      return false;
    }
    lx[lp[k]] = dk;
  }
  l_->minor = l_->n;
  return true;
}

void SparseCholesky::solve(const double* b, double* x, int ncols) {
  const int n = size();
  cholmod_dense bd;
  std::memset(&bd, 0, sizeof(bd));
  bd.nrow = n;
  bd.ncol = ncols;
  bd.nzmax = static_cast<size_t>(n) * ncols;
  bd.d = n;
  bd.x = const_cast<double*>(b);
  bd.xtype = CHOLMOD_REAL;
  bd.dtype = CHOLMOD_DOUBLE;
  if (x_ != nullptr && static_cast<int>(x_->ncol) != ncols) freeWork();
  const OmpThreadCap cap(max_threads_);
  if (cholmod_solve2(CHOLMOD_A, l_, &bd, nullptr, &x_, nullptr, &y_, &e_, &common_) == 0) {
    throw std::runtime_error("CHOLMOD: solve failed");
  }
  std::memcpy(x, x_->x, sizeof(double) * n * ncols);
}

void SparseCholesky::multiply(const double* x, double* y) {
  const int n = size();
  cholmod_dense xd, yd;
  std::memset(&xd, 0, sizeof(xd));
  xd.nrow = n;
  xd.ncol = 1;
  xd.nzmax = n;
  xd.d = n;
  xd.xtype = CHOLMOD_REAL;
  xd.dtype = CHOLMOD_DOUBLE;
  yd = xd;
  xd.x = const_cast<double*>(x);
  yd.x = y;
  double alpha[2] = {1.0, 0.0}, beta[2] = {0.0, 0.0};
  cholmod_sdmult(a_, 0, alpha, beta, &xd, &yd, &common_);
}

double SparseCholesky::factorNonzeros() const { return common_.lnz; }

std::vector<int> fillReducingOrdering(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx,
                                      int method, double* flops) {
  std::vector<int> perm(n);
  if (n == 0) return perm;
  cholmod_common c;
  cholmod_start(&c);
  c.print = 0;
  // Upper triangle with diagonal, pattern only.
  std::vector<int> cp(n + 1, 0), ri;
  ri.reserve(row_idx.size() / 2 + n);
  for (int j = 0; j < n; ++j) {
    for (int k = col_ptr[j]; k < col_ptr[j + 1]; ++k) {
      if (row_idx[k] < j) ri.push_back(row_idx[k]);
    }
    ri.push_back(j);
    cp[j + 1] = static_cast<int>(ri.size());
  }
  cholmod_sparse* a = cholmod_allocate_sparse(n, n, ri.size(), 1, 1, 1, CHOLMOD_PATTERN, &c);
  std::copy(cp.begin(), cp.end(), static_cast<int*>(a->p));
  std::copy(ri.begin(), ri.end(), static_cast<int*>(a->i));
  if (method == 1) {
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_AMD;
  } else if (method == 2) {
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_METIS;
  } else {
    c.nmethods = 2;
    c.method[0].ordering = CHOLMOD_AMD;
    c.method[1].ordering = CHOLMOD_METIS;
  }
  c.postorder = 1;
  cholmod_factor* l = cholmod_analyze(a, &c);
  if (l == nullptr) {
    cholmod_free_sparse(&a, &c);
    cholmod_finish(&c);
    throw std::runtime_error("CHOLMOD: ordering failed");
  }
  std::copy_n(static_cast<const int*>(l->Perm), n, perm.begin());
  if (flops != nullptr) *flops = c.fl;
  cholmod_free_factor(&l, &c);
  cholmod_free_sparse(&a, &c);
  cholmod_finish(&c);
  return perm;
}

Eigen::MatrixXd solveSparseSpd(int n, const std::vector<Eigen::Triplet<double>>& upper, const Eigen::MatrixXd& b) {
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> a(n, n);
  a.setFromTriplets(upper.begin(), upper.end());
  a.makeCompressed();
  SparseCholesky chol;
  std::vector<int> cp(a.outerIndexPtr(), a.outerIndexPtr() + n + 1);
  std::vector<int> ri(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  chol.setPattern(n, cp, ri);
  std::copy(a.valuePtr(), a.valuePtr() + a.nonZeros(), chol.values());
  chol.analyze(/*natural_ordering=*/false);
  if (!chol.factorize()) throw std::runtime_error("linear system is not positive definite");
  Eigen::MatrixXd x(n, b.cols());
  chol.solve(b.data(), x.data(), static_cast<int>(b.cols()));
  return x;
}

}  // namespace cairn::graph_slam::detail
