#include "cairn/copa_map/svgp.hpp"

#include <algorithm>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

#include "gemm.hpp"

namespace cairn::copa_map {
namespace {

// C = alpha op(A) op(B) + beta C through the run-time dispatched GEMM (gemm.hpp: AVX2/AVX-512 where the CPU has
// them; Eigen's own product is compiled for the portable baseline only). Blocks of column-major matrices are
// passed without copies.
// The float overload serves the mixed-precision B·m² products (TrainConfig::mixed_precision).
template <class T>
void gemmT(Eigen::Ref<Eigen::Matrix<T, -1, -1>> C, const Eigen::Ref<const Eigen::Matrix<T, -1, -1>>& A,
           bool trans_a, const Eigen::Ref<const Eigen::Matrix<T, -1, -1>>& B, bool trans_b, T alpha, T beta) {
  detail::GemmArgsT<T> g{trans_a, trans_b, C.rows(), C.cols(), trans_a ? A.rows() : A.cols(), alpha,
                         A.data(), A.outerStride(), B.data(), B.outerStride(), beta, C.data(), C.outerStride()};
  if ((trans_a ? A.cols() : A.rows()) != g.M || (trans_b ? B.rows() : B.cols()) != g.N ||
      (trans_b ? B.cols() : B.rows()) != g.K)
    throw std::logic_error("gemm: dimension mismatch");
  detail::gemm(g);
}

void gemm(Eigen::Ref<Eigen::MatrixXd> C, const Eigen::Ref<const Eigen::MatrixXd>& A, bool trans_a,
          const Eigen::Ref<const Eigen::MatrixXd>& B, bool trans_b, double alpha = 1.0, double beta = 0.0) {
  gemmT<double>(C, A, trans_a, B, trans_b, alpha, beta);
}

void gemm(Eigen::Ref<Eigen::MatrixXf> C, const Eigen::Ref<const Eigen::MatrixXf>& A, bool trans_a,
          const Eigen::Ref<const Eigen::MatrixXf>& B, bool trans_b, float alpha = 1.0f, float beta = 0.0f) {
  gemmT<float>(C, A, trans_a, B, trans_b, alpha, beta);
}

Eigen::MatrixXd product(const Eigen::Ref<const Eigen::MatrixXd>& A, bool trans_a,
                        const Eigen::Ref<const Eigen::MatrixXd>& B, bool trans_b) {
  Eigen::MatrixXd C(trans_a ? A.cols() : A.rows(), trans_b ? B.rows() : B.cols());
  gemm(C, A, trans_a, B, trans_b);
  return C;
}

constexpr double kLog2Pi = 1.83787706640934548356;
constexpr double kSqrtPi = 1.77245385090551602730;

// Small problems run on one thread: on a loaded 2-core machine every OpenMP barrier can cost a scheduler time
// slice, which dwarfs the work of small matrix products. omp_set_num_threads only changes the calling thread's
// setting, and Eigen's GEMM follows omp_get_max_threads() (cairn never calls Eigen::setNbThreads), so this is
// safe while another thread predicts or trains.
class ThreadLimit {
 public:
  explicit ThreadLimit(double work) : saved_(omp_get_max_threads()) {
    if (work < 2e7) omp_set_num_threads(1);
  }
  ~ThreadLimit() { omp_set_num_threads(saved_); }
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  int saved_;
};

double maxInducing(const std::vector<LatentGp>& l) {
  double m = 0;
  for (const auto& x : l) m = std::max(m, static_cast<double>(x.Z.rows()));
  return m;
}

inline double softplus(double x) { return x > 30.0 ? x : std::log1p(std::exp(x)); }
inline double logistic(double x) {
  return x >= 0 ? 1.0 / (1.0 + std::exp(-x)) : std::exp(x) / (1.0 + std::exp(x));
}

double logSumExp(const Eigen::VectorXd& a) {
  const double m = a.maxCoeff();
  return m + std::log((a.array() - m).exp().sum());
}

}  // namespace

void gaussHermite(int order, Eigen::VectorXd& nodes, Eigen::VectorXd& weights) {
  if (order < 1) throw std::invalid_argument("gaussHermite: order must be >= 1");
  // Golub–Welsch: Jacobi matrix of the (physicists') Hermite polynomials.
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(order, order);
  for (int k = 1; k < order; ++k) J(k, k - 1) = J(k - 1, k) = std::sqrt(k / 2.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(J);
  nodes = es.eigenvalues();
  weights = kSqrtPi * es.eigenvectors().row(0).transpose().array().square();
}

// ---------------------------------------------------------------------------------------------- likelihoods

HeteroscedasticGaussianLikelihood::HeteroscedasticGaussianLikelihood(int gh_order, double min_variance)
    : min_var_(min_variance) {
  gaussHermite(gh_order, nodes_, weights_);
}

double HeteroscedasticGaussianLikelihood::variationalExpectations(const Eigen::VectorXd& y,
                                                                  const std::vector<LatentMoments>& q,
                                                                  std::vector<LatentMoments>* grad) const {
  const Eigen::Index n = y.size();
  const auto& f = q[0];
  const auto& g = q[1];
  if (grad) {
    grad->assign(2, LatentMoments{Eigen::VectorXd(n), Eigen::VectorXd(n)});
  }
  const Eigen::Index K = nodes_.size();
  double total = 0.0;
#pragma omp parallel for reduction(+ : total) schedule(static) if (n > 4000)
  for (Eigen::Index i = 0; i < n; ++i) {
    const double r = (y[i] - f.m[i]) * (y[i] - f.m[i]) + f.v[i];
    const double sd = std::sqrt(2.0 * std::max(g.v[i], 0.0));
    double e = 0, inv = 0, dmg = 0, dvg = 0;
    for (Eigen::Index k = 0; k < K; ++k) {
      const double w = weights_[k] / kSqrtPi;
      const double gk = g.m[i] + sd * nodes_[k];
      const double s = softplus(gk) + min_var_;
      // E_q(f)[log N(y | f, s)] in closed form, then Gauss–Hermite over g (eqs. 4.12, 4.19).
      e += w * (-0.5 * kLog2Pi - 0.5 * std::log(s) - r / (2.0 * s));
      inv += w / s;
      const double hp = (-0.5 / s + r / (2.0 * s * s)) * logistic(gk);
      dmg += w * hp;
      dvg += w * hp * nodes_[k];
    }
    total += e;
    if (grad) {
      (*grad)[0].m[i] = (y[i] - f.m[i]) * inv;
      (*grad)[0].v[i] = -0.5 * inv;
      (*grad)[1].m[i] = dmg;
      (*grad)[1].v[i] = sd > 1e-300 ? dvg / sd : 0.0;
    }
  }
  return total;
}

void HeteroscedasticGaussianLikelihood::predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean,
                                                Eigen::VectorXd& var) const {
  const Eigen::Index n = q[0].m.size();
  mean = q[0].m;
  var.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double sd = std::sqrt(2.0 * std::max(q[1].v[i], 0.0));
    double es = 0;
    for (Eigen::Index k = 0; k < nodes_.size(); ++k)
      es += weights_[k] / kSqrtPi * (softplus(q[1].m[i] + sd * nodes_[k]) + min_var_);
    var[i] = q[0].v[i] + es;  // law of total variance, E over g by Gauss–Hermite (eq. 4.19)
  }
}

Eigen::VectorXd HeteroscedasticGaussianLikelihood::logPredictiveDensity(const Eigen::VectorXd& y,
                                                                        const std::vector<LatentMoments>& q) const {
  const Eigen::Index n = y.size(), K = nodes_.size();
  Eigen::VectorXd out(n), a(K);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double sd = std::sqrt(2.0 * std::max(q[1].v[i], 0.0));
    for (Eigen::Index k = 0; k < K; ++k) {
      const double s = q[0].v[i] + softplus(q[1].m[i] + sd * nodes_[k]) + min_var_;
      const double d = y[i] - q[0].m[i];
      a[k] = std::log(weights_[k] / kSqrtPi) - 0.5 * (kLog2Pi + std::log(s) + d * d / s);
    }
    out[i] = logSumExp(a);
  }
  return out;
}

double GaussianLikelihood::variationalExpectations(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q,
                                                   std::vector<LatentMoments>* grad) const {
  const auto& f = q[0];
  const Eigen::ArrayXd d = y - f.m;
  if (grad) {
    grad->assign(1, LatentMoments{});
    (*grad)[0].m = (d / var_).matrix();
    (*grad)[0].v = Eigen::VectorXd::Constant(y.size(), -0.5 / var_);
  }
  return (-0.5 * (kLog2Pi + std::log(var_)) - (d.square() + f.v.array()) / (2 * var_)).sum();
}

void GaussianLikelihood::predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean,
                                 Eigen::VectorXd& var) const {
  mean = q[0].m;
  var = q[0].v.array() + var_;
}

Eigen::VectorXd GaussianLikelihood::logPredictiveDensity(const Eigen::VectorXd& y,
                                                         const std::vector<LatentMoments>& q) const {
  const Eigen::ArrayXd s = q[0].v.array() + var_;
  return (-0.5 * (kLog2Pi + s.log() + (y - q[0].m).array().square() / s)).matrix();
}

PoissonLikelihood::PoissonLikelihood(int gh_order) { gaussHermite(gh_order, nodes_, weights_); }

double PoissonLikelihood::variationalExpectations(const Eigen::VectorXd& y, const std::vector<LatentMoments>& q,
                                                  std::vector<LatentMoments>* grad) const {
  // E_q[y f - exp(f) - log y!] = y m - exp(m + v/2) - lgamma(y+1) (GP-Hom, §4.3.2).
  const auto& f = q[0];
  const Eigen::Index n = y.size();
  if (grad) grad->assign(1, LatentMoments{Eigen::VectorXd(n), Eigen::VectorXd(n)});
  double total = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double e = std::exp(f.m[i] + 0.5 * f.v[i]);
    total += y[i] * f.m[i] - e - std::lgamma(y[i] + 1.0);
    if (grad) {
      (*grad)[0].m[i] = y[i] - e;
      (*grad)[0].v[i] = -0.5 * e;
    }
  }
  return total;
}

void PoissonLikelihood::predict(const std::vector<LatentMoments>& q, Eigen::VectorXd& mean,
                                Eigen::VectorXd& var) const {
  const Eigen::ArrayXd m = q[0].m.array(), v = q[0].v.array();
  mean = (m + 0.5 * v).exp().matrix();
  var = (mean.array() + (v.exp() - 1.0) * (2.0 * m + v).exp()).matrix();
}

Eigen::VectorXd PoissonLikelihood::logPredictiveDensity(const Eigen::VectorXd& y,
                                                        const std::vector<LatentMoments>& q) const {
  const Eigen::Index n = y.size(), K = nodes_.size();
  Eigen::VectorXd out(n), a(K);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double sd = std::sqrt(2.0 * std::max(q[0].v[i], 0.0));
    for (Eigen::Index k = 0; k < K; ++k) {
      const double fk = q[0].m[i] + sd * nodes_[k];
      a[k] = std::log(weights_[k] / kSqrtPi) + y[i] * fk - std::exp(fk) - std::lgamma(y[i] + 1.0);
    }
    out[i] = logSumExp(a);
  }
  return out;
}

std::unique_ptr<Likelihood> makeLikelihood(const std::string& type, double param) {
  if (type == "heteroscedastic_gaussian_softplus")
    return std::make_unique<HeteroscedasticGaussianLikelihood>(static_cast<int>(param));
  if (type == "gaussian") return std::make_unique<GaussianLikelihood>(param);
  if (type == "poisson_exp") return std::make_unique<PoissonLikelihood>(static_cast<int>(param));
  throw std::invalid_argument("makeLikelihood: unknown likelihood '" + type + "'");
}

// ------------------------------------------------------------------------------------------------- latents

LatentGp::LatentGp(std::unique_ptr<Kernel> k, Eigen::MatrixXd z, double init_sqrt_scale)
    : kernel(std::move(k)), Z(std::move(z)) {
  mu = Eigen::VectorXd::Zero(Z.rows());
  // GPflow-style start q(u) = N(0, s² K_uu): L = s chol(K_uu).
  Eigen::MatrixXd Kuu = kernel->K(Z, Z);
  Kuu.diagonal().array() += 1e-6 * std::max(1.0, Kuu.diagonal().mean());
  Eigen::LLT<Eigen::MatrixXd> llt(Kuu);
  L = init_sqrt_scale * Eigen::MatrixXd(llt.matrixL());
}

LatentGp::LatentGp(const LatentGp& o)
    : kernel(o.kernel ? o.kernel->clone() : nullptr), Z(o.Z), mu(o.mu), L(o.L), precision(o.precision) {}

LatentGp& LatentGp::operator=(const LatentGp& o) {
  if (this != &o) {
    kernel = o.kernel ? o.kernel->clone() : nullptr;
    Z = o.Z;
    mu = o.mu;
    L = o.L;
    precision = o.precision;
  }
  return *this;
}

SvgpModel::SvgpModel(std::vector<LatentGp> latents, std::unique_ptr<Likelihood> lik, double jitter)
    : latents_(std::move(latents)), lik_(std::move(lik)), jitter_(jitter) {
  if (!lik_ || static_cast<int>(latents_.size()) != lik_->numLatent())
    throw std::invalid_argument("SvgpModel: number of latents does not match the likelihood");
}

SvgpModel::SvgpModel(const SvgpModel& o)
    : latents_(o.latents_),
      lik_(o.lik_ ? o.lik_->clone() : nullptr),
      jitter_(o.jitter_),
      mixed_precision_(o.mixed_precision_) {}

SvgpModel& SvgpModel::operator=(const SvgpModel& o) {
  if (this != &o) {
    latents_ = o.latents_;
    lik_ = o.lik_ ? o.lik_->clone() : nullptr;
    jitter_ = o.jitter_;
    mixed_precision_ = o.mixed_precision_;
  }
  return *this;
}

namespace {

// Block-column helpers for the O(m³) and O(B m²) products with triangular factors. Column block [j0, j0 + w) of
// each result only involves rows/columns >= j0 of the triangular operand, so a triangular solve or product costs
// a third (solve with a triangular right-hand side) or half (products) of the dense one, and the blocks are
// independent: they run on both cores (OpenMP, dynamic schedule since the blocks differ in size; Eigen's products
// inside run single-threaded). Eigen's own triangular solves and products are single-threaded.
constexpr Eigen::Index kColBlock = 96;
// Below this size the blocks run on one thread: with m = 478 (the reduced ATC configuration) a natural-gradient
// step costs 0.006 CPU-s on one thread but 0.054 CPU-s (0.24 s wall) on two of a loaded 2-core box, where every
// join of the ~20 small parallel regions waits for a scheduler slice (bench_copa_step, docs/benchmarks.md).
constexpr Eigen::Index kParallelBlocksMin = 6 * kColBlock;

template <class F>
void forColumnBlocks(Eigen::Index m, F&& f) {
  const Eigen::Index nb = (m + kColBlock - 1) / kColBlock;
  if (m <= kParallelBlocksMin) {
    ThreadLimit one(0.0);  // and no parallel GEMM inside the blocks either
    for (Eigen::Index b = 0; b < nb; ++b) f(b * kColBlock, std::min(kColBlock, m - b * kColBlock));
    return;
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (Eigen::Index b = 0; b < nb; ++b) f(b * kColBlock, std::min(kColBlock, m - b * kColBlock));
}

// Inverse of a small lower-triangular diagonal block (Eigen's portable triangular solve; kColBlock³/3 flops).
Eigen::MatrixXd smallLowerInverse(const Eigen::Ref<const Eigen::MatrixXd>& D) {
  Eigen::MatrixXd X = Eigen::MatrixXd::Identity(D.rows(), D.cols());
  D.triangularView<Eigen::Lower>().solveInPlace(X);
  return X;
}

// L⁻¹ for lower-triangular L (m³/3 flops). Column block j of the inverse is found block row by block row:
// X_jj = L_jj⁻¹, X_ij = -L_ii⁻¹ Σ_{j<=k<i} L_ik X_kj, the sum being one dispatched GEMM; column blocks are
// independent and run on both cores. (Multiplying by precomputed L_ii⁻¹ instead of the triangular solve was
// measurably less accurate on ill-conditioned K_uu: GemmVariantsAndBatchSplitAgreeWithThePortableSerialOne.)
Eigen::MatrixXd lowerInverse(const Eigen::MatrixXd& L) {
  const Eigen::Index m = L.rows();
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(m, m);
  forColumnBlocks(m, [&](Eigen::Index j0, Eigen::Index w) {
    for (Eigen::Index i0 = j0; i0 < m; i0 += kColBlock) {
      const Eigen::Index wi = std::min(kColBlock, m - i0);
      auto Xi = X.block(i0, j0, wi, w);
      if (i0 == j0)
        Xi.setIdentity();
      else
        gemm(Xi, L.block(i0, j0, wi, i0 - j0), false, X.block(j0, j0, i0 - j0, w), false, -1.0, 0.0);
      L.block(i0, i0, wi, wi).triangularView<Eigen::Lower>().solveInPlace(Xi);
    }
  });
  return X;
}

// Lower Cholesky factor of a symmetric positive definite A (lower triangle read), right-looking by blocks of
// kColBlock: the diagonal block by Eigen's LLT, the panel by a triangular solve and the trailing update
// A22 -= L21 L21ᵀ (m³/3 of the m³/3 + O(m² nb) flops) by the dispatched GEMM, one column block of the lower
// triangle at a time, on both cores. Returns false when A is not positive definite (like Eigen::LLT::info()).
bool choleskyLower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L) {
  const Eigen::Index m = A.rows();
  L = A;
  for (Eigen::Index k = 0; k < m; k += kColBlock) {
    const Eigen::Index w = std::min(kColBlock, m - k), r = m - k - w;
    Eigen::LLT<Eigen::MatrixXd> llt(L.block(k, k, w, w));
    if (llt.info() != Eigen::Success) return false;
    L.block(k, k, w, w) = llt.matrixL();
    if (r == 0) break;
    // L21 = A21 L11⁻ᵀ as one dispatched GEMM with the small inverse (Eigen's triangular solve is portable code).
    const Eigen::MatrixXd L11inv = smallLowerInverse(L.block(k, k, w, w));
    Eigen::MatrixXd P(r, w);
    {
      ThreadLimit one(0.0);  // r x w x w: a fork/join of its own would cost more than it saves on a busy box
      gemm(P, L.block(k + w, k, r, w), false, L11inv, true);
    }
    L.block(k + w, k, r, w) = P;
    forColumnBlocks(r, [&](Eigen::Index j0, Eigen::Index wj) {
      gemm(L.block(k + w + j0, k + w + j0, r - j0, wj), P.bottomRows(r - j0), false, P.middleRows(j0, wj), true,
           -1.0, 1.0);
    });
  }
  L.triangularView<Eigen::StrictlyUpper>().setZero();
  return L.allFinite();
}


// A L for an n x m A and lower-triangular m x m L: n m² flops (m³/3 when A is lower triangular too, `a_lower`;
// its strict upper triangle must then be zero, as lowerInverse leaves it: block row i0 of column block j0 is one
// dispatched GEMM over columns j0 .. i0 + wi of A, the zeros above A's diagonal included).
template <class M>
M timesLower(const M& A, const M& L, bool a_lower = false) {
  const Eigen::Index m = L.rows();
  M out = a_lower ? M::Zero(m, m) : M(A.rows(), m);
  forColumnBlocks(m, [&](Eigen::Index j0, Eigen::Index w) {
    const Eigen::Index h = m - j0;
    M Lb = L.block(j0, j0, h, w);
    Lb.topRows(w).template triangularView<Eigen::StrictlyUpper>().setZero();
    if (a_lower) {
      for (Eigen::Index i0 = j0; i0 < m; i0 += kColBlock) {
        const Eigen::Index wi = std::min(kColBlock, m - i0), k = i0 + wi - j0;
        gemm(out.block(i0, j0, wi, w), A.block(i0, j0, wi, k), false, Lb.topRows(k), false);
      }
    } else {
      gemm(out.middleCols(j0, w), A.rightCols(h), false, Lb, false);
    }
  });
  return out;
}

// Aᵀ diag(d) A (symmetric; only the lower half is multiplied, then mirrored): n m² flops instead of 2 n m².
// `a_lower`: A is square and lower triangular (zeros above the diagonal), so rows above column block j0 of A are
// zero and skipped (2m³/3 instead of m³ flops, e.g. K⁻¹ = L_K⁻ᵀ L_K⁻¹).
template <class M, class V>
M weightedGram(const M& A, const V& d, bool a_lower = false) {
  const Eigen::Index m = A.cols();
  M out(m, m);
  forColumnBlocks(m, [&](Eigen::Index j0, Eigen::Index w) {
    const Eigen::Index r0 = a_lower ? j0 : 0, h = A.rows() - r0;
    const M DA = d.segment(r0, h).asDiagonal() * A.block(r0, j0, h, w);
    gemm(out.block(j0, j0, m - j0, w), A.block(r0, j0, h, m - j0), true, DA, false);
  });
  out.template triangularView<Eigen::StrictlyUpper>() = out.transpose();
  return out;
}

struct LatentCache {
  Eigen::MatrixXd Knu, A, AL;
  Eigen::MatrixXf Af, ALf;  // mixed precision: A and A L in single precision
  Eigen::VectorXd kdiag;
};

// Rows of a mini-batch block per single-precision partial sum of Aᵀ diag(d) A, added up in double.
constexpr Eigen::Index kMixedRowChunk = 256;

// q(f) marginals on a batch given K_uu⁻¹ (eqs. 4.13-4.14): m = A μ, v = k_nn - diag(A K_un) + diag(A S Aᵀ).
// Lf != nullptr: mixed precision (TrainConfig::mixed_precision). A = K_nu K_uu⁻¹ stays double (it carries K_uu's
// conditioning, κ ~ 1e5-1e6 at the jitter used); A L (B m² flops) is formed in single precision from A rounded
// to float, its squared row norms are summed in double.
void computeMoments(const LatentGp& lat, const Eigen::MatrixXd& Kinv, const Eigen::MatrixXf* Lf,
                    const Eigen::MatrixXd& X, LatentCache& c, LatentMoments& q) {
  c.Knu = lat.kernel->K(X, lat.Z);
  c.kdiag = lat.kernel->Kdiag(X);
  c.A = product(c.Knu, false, Kinv, false);  // A = K_nu K_uu⁻¹ (GEMM; faster than two triangular solves)
  q.m.noalias() = c.A * lat.mu;
  q.v = c.kdiag - (c.A.array() * c.Knu.array()).rowwise().sum().matrix();
  if (Lf) {
    c.Af = c.A.cast<float>();
    c.ALf = timesLower(c.Af, *Lf);
    q.v += c.ALf.cast<double>().array().square().rowwise().sum().matrix();
  } else {
    c.AL = timesLower(c.A, lat.L);
    q.v += c.AL.array().square().rowwise().sum().matrix();
  }
  q.v = q.v.cwiseMax(1e-12);
}

// Aᵀ diag(d) A from the single-precision A: float partial sums over kMixedRowChunk rows, accumulated in double
// (the accumulation error of one float sum grows with its length; the chunks bound it).
Eigen::MatrixXd weightedGramMixed(const Eigen::MatrixXf& Af, const Eigen::VectorXd& d) {
  const Eigen::Index n = Af.rows(), m = Af.cols();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(m, m);
  const Eigen::VectorXf df = d.cast<float>();
  for (Eigen::Index r0 = 0; r0 < n; r0 += kMixedRowChunk) {
    const Eigen::Index len = std::min(kMixedRowChunk, n - r0);
    const Eigen::MatrixXf part = weightedGram(Eigen::MatrixXf(Af.middleRows(r0, len)), df.segment(r0, len));
    out += part.cast<double>();
  }
  return out;
}

Eigen::MatrixXd precisionOf(const LatentGp& lat) {
  if (lat.precision.rows() == lat.L.rows()) return lat.precision;
  return weightedGram(lowerInverse(lat.L), Eigen::VectorXd::Ones(lat.L.rows()), true);
}

}  // namespace

const SvgpModel::KuuCache& SvgpModel::kuu(int k) const {
  if (kuu_cache_.size() != latents_.size()) {
    kuu_cache_.clear();
    kuu_cache_.resize(latents_.size());
  }
  KuuCache& c = kuu_cache_[static_cast<std::size_t>(k)];
  const LatentGp& lat = latents_[static_cast<std::size_t>(k)];
  Eigen::VectorXd key(lat.kernel->numParams() + 1);
  key << lat.kernel->params(), static_cast<double>(lat.Z.rows());
  if (c.params.size() == key.size() && c.params == key && c.Kinv.rows() == lat.Z.rows() && c.Z == lat.Z) return c;
  Eigen::MatrixXd Kuu = lat.kernel->K(lat.Z, lat.Z);
  Kuu.diagonal().array() += jitter_;
  if (!choleskyLower(Kuu, c.Lk)) throw std::runtime_error("SVGP: K_uu is not positive definite");
  c.Linv = lowerInverse(c.Lk);
  c.Kinv = weightedGram(c.Linv, Eigen::VectorXd::Ones(lat.Z.rows()), true);  // K⁻¹ = L_K⁻ᵀ L_K⁻¹
  c.params = key;
  c.Z = lat.Z;
  return c;
}

namespace {

// Smallest mini-batch block per thread in evaluate().
constexpr Eigen::Index kMinRowsPerThread = 128;

// Sums over one block of mini-batch rows: everything in the ELBO and its gradients up to the sums over the batch
// is row-local (moments, likelihood expectations, Aᵀ ∂E/∂m, Aᵀ diag(∂E/∂v) A, the K_nu and diag K_nn parts of
// the kernel gradients).
struct RowBlockSums {
  double ell = 0;
  std::vector<Eigen::VectorXd> b, hyper;
  std::vector<Eigen::MatrixXd> Q, dnu;
  std::string error;
};

}  // namespace

ElboEvaluation SvgpModel::evaluate(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, double scale,
                                   bool hyper_grad, bool z_grad) const {
  const int nl = static_cast<int>(latents_.size());
  const auto unl = static_cast<std::size_t>(nl);
  // K_uu factors first (the cache is not thread-safe) and the m x m quantities every row block needs.
  std::vector<const KuuCache*> kc(unl);
  std::vector<Eigen::VectorXd> beta(unl);
  std::vector<Eigen::MatrixXd> V(unl);
  for (std::size_t k = 0; k < unl; ++k) {
    kc[k] = &kuu(static_cast<int>(k));
    beta[k] = kc[k]->Kinv * latents_[k].mu;  // β = K⁻¹μ
    // V = K⁻¹L, so that K⁻¹S = V Lᵀ and K⁻¹SK⁻¹ = V Vᵀ: 5 m³ flops instead of forming S and K⁻¹S (7 m³).
    if (hyper_grad || z_grad) V[k] = timesLower(kc[k]->Kinv, latents_[k].L);
  }
  std::vector<Eigen::MatrixXf> Lf(mixed_precision_ ? unl : 0);
  for (std::size_t k = 0; k < Lf.size(); ++k) Lf[k] = latents_[k].L.cast<float>();

  // The mini-batch is split into one block of rows per core: one fork/join per evaluation instead of one per
  // matrix product, which matters on a loaded 2-core machine where every join can wait for a scheduler slice
  // (docs/benchmarks.md, copa_map). Products inside a block run single-threaded (nested regions are inactive).
  const Eigen::Index n = X.rows();
  const int T = static_cast<int>(std::max<Eigen::Index>(
      1, std::min<Eigen::Index>(omp_get_max_threads(), n / kMinRowsPerThread)));
  std::vector<RowBlockSums> parts(static_cast<std::size_t>(T));
#pragma omp parallel num_threads(T) if (T > 1)
  {
    const int t = omp_get_thread_num();
    RowBlockSums& P = parts[static_cast<std::size_t>(t)];
    // No nested teams: Eigen's GEMM decides on threads by omp_get_num_threads(), which is 1 again inside an
    // inactive nested region, and would then start its own parallel product within this block.
    omp_set_num_threads(1);
    try {
      const Eigen::Index r0 = n * t / T, len = n * (t + 1) / T - r0;
      const Eigen::MatrixXd Xt = X.middleRows(r0, len);
      const Eigen::VectorXd yt = y.segment(r0, len);
      std::vector<LatentCache> cache(unl);
      std::vector<LatentMoments> q(unl), dq;
      for (std::size_t k = 0; k < unl; ++k)
        computeMoments(latents_[k], kc[k]->Kinv, mixed_precision_ ? &Lf[k] : nullptr, Xt, cache[k], q[k]);
      P.ell = lik_->variationalExpectations(yt, q, &dq);
      P.b.resize(unl);
      P.Q.resize(unl);
      P.hyper.resize(unl);
      P.dnu.resize(unl);
      for (std::size_t k = 0; k < unl; ++k) {
        const LatentGp& lat = latents_[k];
        const LatentCache& c = cache[k];
        P.b[k].noalias() = c.A.transpose() * dq[k].m;
        P.Q[k] = mixed_precision_ ? weightedGramMixed(c.Af, dq[k].v) : weightedGram(c.A, dq[k].v);
        if (!hyper_grad && !z_grad) continue;
        // ∂(scale E - KL)/∂K_nu = scale [∂E/∂m βᵀ + 2 diag(∂E/∂v)(A S K⁻¹ - A)], chained into the kernel.
        Eigen::MatrixXd ASK = c.A;
        gemm(ASK, mixed_precision_ ? Eigen::MatrixXd(c.ALf.cast<double>()) : c.AL, false, V[k], true, 1.0,
             -1.0);  // A S K⁻¹ - A (double: in float, V = K⁻¹L's large entries cost up to 2e-3 of the gradient)
        Eigen::MatrixXd Gnu = dq[k].m * beta[k].transpose();
        Gnu.noalias() += 2.0 * (dq[k].v.asDiagonal() * ASK);
        Gnu *= scale;
        if (hyper_grad) P.hyper[k] = lat.kernel->gradK(Xt, lat.Z, Gnu) + lat.kernel->gradKdiag(Xt, scale * dq[k].v);
        if (z_grad) lat.kernel->gradInputs(Xt, lat.Z, Gnu, nullptr, &P.dnu[k]);
      }
    } catch (const std::exception& e) {
      P.error = e.what();
    }
  }
  for (const auto& P : parts)
    if (!P.error.empty()) throw std::runtime_error(P.error);

  ElboEvaluation ev;
  ev.latent.resize(unl);
  if (hyper_grad) ev.hyper_grad = Eigen::VectorXd::Zero(numHyperParams());
  if (z_grad) ev.z_grad.resize(unl);
  for (const auto& P : parts) ev.ell += P.ell;
  int offset = 0;
  for (std::size_t k = 0; k < unl; ++k) {
    const LatentGp& lat = latents_[k];
    auto& pl = ev.latent[k];
    const Eigen::Index m = lat.Z.rows();
    pl.b = parts[0].b[k];
    pl.Q = std::move(parts[0].Q[k]);
    for (std::size_t t = 1; t < parts.size(); ++t) {
      pl.b += parts[t].b[k];
      pl.Q += parts[t].Q[k];
    }
    const Eigen::MatrixXd& Kinv = kc[k]->Kinv;
    // KL(q(u) || p(u)) = ½[tr(K⁻¹S) + μᵀK⁻¹μ - m + log|K| - log|S|] (eq. 4.12); tr(K⁻¹S) = ‖L_K⁻¹ L‖²_F.
    const Eigen::MatrixXd LKL = timesLower(kc[k]->Linv, lat.L, true);  // L_K⁻¹ L (both lower triangular)
    const double logdetK = 2.0 * kc[k]->Lk.diagonal().array().log().sum();
    const double logdetS = 2.0 * lat.L.diagonal().array().abs().log().sum();
    ev.kl += 0.5 * (LKL.squaredNorm() + lat.mu.dot(beta[k]) - static_cast<double>(m) + logdetK - logdetS);
    pl.grad_mu = scale * pl.b - beta[k];
    pl.Kinv = Kinv;
    if (!hyper_grad && !z_grad) continue;
    // ∂/∂K_uu of scale E - KL. Only the symmetric part matters (K_uu is symmetric), so K⁻¹SQ + QSK⁻¹ enters as
    // 2 K⁻¹SQ. The two S terms share the factor K⁻¹S = V Lᵀ:
    // -2 scale K⁻¹SQ + ½ K⁻¹SK⁻¹ = V [(½ K⁻¹ - 2 scale Q) L]ᵀ, one triangular (m³) and one dense (2m³) product
    // instead of forming K⁻¹SQ and K⁻¹SK⁻¹ = VVᵀ separately (4m³).
    const Eigen::MatrixXd P = 0.5 * Kinv - (2.0 * scale) * pl.Q;
    Eigen::MatrixXd Guu = product(V[k], false, timesLower(P, lat.L), true);
    Guu += scale * (pl.Q - pl.b * beta[k].transpose()) - 0.5 * (Kinv - beta[k] * beta[k].transpose());
    // Symmetrize and fold onto the lower triangle: the kernel gradient skips the zero upper half.
    Eigen::MatrixXd Gs = Eigen::MatrixXd::Zero(m, m);
    Gs.triangularView<Eigen::StrictlyLower>() = Guu + Guu.transpose();
    Gs.diagonal() = Guu.diagonal();
    Guu = std::move(Gs);
    const int np = lat.kernel->numParams();
    if (hyper_grad) {
      auto seg = ev.hyper_grad.segment(offset, np);
      seg = lat.kernel->gradK(lat.Z, lat.Z, Guu);
      for (const auto& P : parts) seg += P.hyper[k];
    }
    offset += np;
    if (z_grad) {
      // Z enters K_nu (second argument) and both arguments of K_uu; k(x, x) does not depend on x.
      Eigen::MatrixXd duu1, duu2;
      lat.kernel->gradInputs(lat.Z, lat.Z, Guu, &duu1, &duu2);
      ev.z_grad[k] = duu1 + duu2;
      for (const auto& P : parts) ev.z_grad[k] += P.dnu[k];
    }
  }
  ev.elbo = scale * ev.ell - ev.kl;
  return ev;
}

double SvgpModel::naturalGradientStep(int k, const ElboEvaluation& ev, double scale, double gamma) {
  LatentGp& lat = latents_[k];
  const auto& pl = ev.latent[k];
  // Natural parameters θ1 = S⁻¹μ, θ2 = -½S⁻¹; the natural gradient equals the gradient w.r.t. the expectation
  // parameters, giving Λ' = (1-γ)Λ + γ(K⁻¹ - 2 s Q), θ1' = (1-γ)θ1 + γ s (b - 2Qμ) (Salimbeni et al. 2018).
  const Eigen::MatrixXd Lambda = precisionOf(lat);
  const Eigen::VectorXd theta1 = Lambda * lat.mu;
  const Eigen::MatrixXd target = pl.Kinv - 2.0 * scale * pl.Q;
  const Eigen::VectorXd target1 = scale * (pl.b - 2.0 * pl.Q * lat.mu);
  for (int attempt = 0; attempt < 12; ++attempt, gamma *= 0.5) {
    Eigen::MatrixXd Ln = (1.0 - gamma) * Lambda + gamma * target;
    if (setNaturalParams(lat, std::move(Ln), (1.0 - gamma) * theta1 + gamma * target1)) return gamma;
  }
  return 0.0;
}

bool setNaturalParams(LatentGp& lat, Eigen::MatrixXd Lambda, const Eigen::VectorXd& theta1) {
  Lambda = 0.5 * (Lambda + Lambda.transpose()).eval();
  // Lower-triangular root of S = Λ⁻¹ from the Cholesky factor of the reversed precision.
  Eigen::MatrixXd M;
  if (!choleskyLower(Lambda.reverse(), M)) return false;
  const Eigen::MatrixXd Minv = lowerInverse(M);
  Eigen::MatrixXd Lnew = Minv.transpose().reverse();
  Lnew.triangularView<Eigen::StrictlyUpper>().setZero();
  const Eigen::VectorXd mu_new = Lnew * (Lnew.transpose() * theta1);
  if (!Lnew.allFinite() || !mu_new.allFinite()) return false;
  lat.L = std::move(Lnew);
  lat.mu = mu_new;
  lat.precision = std::move(Lambda);
  return true;
}

LatentMoments SvgpModel::latentMoments(int k, const Eigen::MatrixXd& X) const {
  const LatentGp& lat = latents_[static_cast<std::size_t>(k)];
  LatentMoments out{Eigen::VectorXd(X.rows()), Eigen::VectorXd(X.rows())};
  const Eigen::Index m = lat.Z.rows();
  ThreadLimit threads(static_cast<double>(X.rows()) * m * m + static_cast<double>(m) * m * m);
  Eigen::MatrixXd Kuu = lat.kernel->K(lat.Z, lat.Z);
  Kuu.diagonal().array() += jitter_;
  Eigen::LLT<Eigen::MatrixXd> llt(Kuu);
  if (llt.info() != Eigen::Success) throw std::runtime_error("SVGP: K_uu is not positive definite");
  // m = K_nu β with β = K⁻¹μ; v = k_nn + diag(K_nu B K_un) with B = K⁻¹ (S - K) K⁻¹ (eqs. 4.13-4.16).
  const Eigen::VectorXd beta = llt.solve(lat.mu);
  const Eigen::MatrixXd KinvL = llt.solve(lat.L.triangularView<Eigen::Lower>().toDenseMatrix());
  Eigen::MatrixXd Bm = llt.solve(Eigen::MatrixXd::Identity(m, m));
  gemm(Bm, KinvL, false, KinvL, true, 1.0, -1.0);
  const Eigen::Index chunk = 4000;
  for (Eigen::Index s = 0; s < X.rows(); s += chunk) {
    const Eigen::Index len = std::min(chunk, X.rows() - s);
    const Eigen::MatrixXd Knu = lat.kernel->K(X.middleRows(s, len), lat.Z);
    out.m.segment(s, len).noalias() = Knu * beta;
    const Eigen::MatrixXd KB = product(Knu, false, Bm, false);
    out.v.segment(s, len) =
        (lat.kernel->Kdiag(X.middleRows(s, len)) + (KB.array() * Knu.array()).rowwise().sum().matrix()).cwiseMax(1e-12);
  }
  return out;
}

void SvgpModel::predictY(const Eigen::MatrixXd& X, Eigen::VectorXd& mean, Eigen::VectorXd& var) const {
  std::vector<LatentMoments> q;
  for (int k = 0; k < static_cast<int>(latents_.size()); ++k) q.push_back(latentMoments(k, X));
  lik_->predict(q, mean, var);
}

Eigen::VectorXd SvgpModel::logPredictiveDensity(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) const {
  std::vector<LatentMoments> q;
  for (int k = 0; k < static_cast<int>(latents_.size()); ++k) q.push_back(latentMoments(k, X));
  return lik_->logPredictiveDensity(y, q);
}

int SvgpModel::numHyperParams() const {
  int n = 0;
  for (const auto& l : latents_) n += l.kernel->numParams();
  return n;
}

Eigen::VectorXd SvgpModel::hyperParams() const {
  Eigen::VectorXd p(numHyperParams());
  int o = 0;
  for (const auto& l : latents_) {
    p.segment(o, l.kernel->numParams()) = l.kernel->params();
    o += l.kernel->numParams();
  }
  return p;
}

void SvgpModel::setHyperParams(const Eigen::VectorXd& p) {
  int o = 0;
  for (auto& l : latents_) {
    l.kernel->setParams(p.segment(o, l.kernel->numParams()));
    o += l.kernel->numParams();
  }
}

Eigen::VectorXd SvgpModel::hyperLowerBounds() const {
  Eigen::VectorXd p(numHyperParams());
  int o = 0;
  for (const auto& l : latents_) {
    p.segment(o, l.kernel->numParams()) = l.kernel->lowerBounds();
    o += l.kernel->numParams();
  }
  return p;
}

Eigen::VectorXd SvgpModel::hyperUpperBounds() const {
  Eigen::VectorXd p(numHyperParams());
  int o = 0;
  for (const auto& l : latents_) {
    p.segment(o, l.kernel->numParams()) = l.kernel->upperBounds();
    o += l.kernel->numParams();
  }
  return p;
}

// ----------------------------------------------------------------------------------------------- training

namespace {

// Running sum of iterates for Polyak–Ruppert averaging: the natural parameters (Λ = S⁻¹, θ1 = S⁻¹μ) of every
// q(u_k), whose natural-gradient update is a convex combination in exactly these coordinates (so their average
// is again a valid Gaussian), the unconstrained kernel hyperparameters and the inducing inputs.
struct IterateSum {
  std::vector<Eigen::MatrixXd> Lambda, Z;
  std::vector<Eigen::VectorXd> theta1;
  Eigen::VectorXd hyper;
  int count = 0;

  void add(const SvgpModel& model) {
    const auto& lats = model.latents();
    if (count == 0) {
      Lambda.clear();
      theta1.clear();
      Z.clear();
      for (const auto& lat : lats) {
        Lambda.push_back(Eigen::MatrixXd::Zero(lat.Z.rows(), lat.Z.rows()));
        theta1.push_back(Eigen::VectorXd::Zero(lat.Z.rows()));
        Z.push_back(Eigen::MatrixXd::Zero(lat.Z.rows(), lat.Z.cols()));
      }
      hyper = Eigen::VectorXd::Zero(model.numHyperParams());
    }
    for (std::size_t k = 0; k < lats.size(); ++k) {
      const Eigen::MatrixXd P = precisionOf(lats[k]);
      Lambda[k] += P;
      theta1[k] += P * lats[k].mu;
      Z[k] += lats[k].Z;
    }
    hyper += model.hyperParams();
    ++count;
  }
  void merge(const IterateSum& o) {
    if (o.count == 0) return;
    if (count == 0) {
      *this = o;
      return;
    }
    for (std::size_t k = 0; k < Lambda.size(); ++k) {
      Lambda[k] += o.Lambda[k];
      theta1[k] += o.theta1[k];
      Z[k] += o.Z[k];
    }
    hyper += o.hyper;
    count += o.count;
  }
  bool apply(SvgpModel& model) const {
    const double w = 1.0 / count;
    SvgpModel out = model;
    for (std::size_t k = 0; k < Lambda.size(); ++k) {
      out.latents()[k].Z = w * Z[k];
      if (!setNaturalParams(out.latents()[k], w * Lambda[k], w * theta1[k])) return false;
    }
    out.setHyperParams(w * hyper);
    model = std::move(out);
    return true;
  }
};

}  // namespace

TrainConfig::StepDecay stepDecayFromName(const std::string& name) {
  if (name == "constant") return TrainConfig::StepDecay::Constant;
  if (name == "invsqrt") return TrainConfig::StepDecay::InvSqrt;
  if (name == "plateau") return TrainConfig::StepDecay::Plateau;
  throw std::invalid_argument("step decay '" + name + "': expected constant, invsqrt or plateau");
}

const char* stepDecayName(TrainConfig::StepDecay d) {
  switch (d) {
    case TrainConfig::StepDecay::InvSqrt: return "invsqrt";
    case TrainConfig::StepDecay::Plateau: return "plateau";
    case TrainConfig::StepDecay::Constant: break;
  }
  return "constant";
}

TrainReport trainSvgp(SvgpModel& model, const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                      const TrainConfig& cfg) {
  TrainReport rep;
  const Eigen::Index n = X.rows();
  if (n == 0) throw std::invalid_argument("trainSvgp: empty training set");
  if (y.size() != n) throw std::invalid_argument("trainSvgp: X and y sizes differ");
  if (!X.allFinite() || !y.allFinite()) throw std::invalid_argument("trainSvgp: NaN or Inf in training data");
  const auto t_start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  const Eigen::Index B = std::min<Eigen::Index>(std::max(1, cfg.batch_size), n);
  const double mmax = maxInducing(model.latents());
  ThreadLimit threads(static_cast<double>(B) * mmax * mmax + mmax * mmax * mmax);
  std::mt19937_64 rng(cfg.seed);
  std::vector<Eigen::Index> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), 0);

  // Adam state (Kingma & Ba 2014) on the unconstrained hyperparameters; maximizes the ELBO.
  const int np = model.numHyperParams();
  Eigen::VectorXd am = Eigen::VectorXd::Zero(np), av = Eigen::VectorXd::Zero(np);
  const Eigen::VectorXd lo = model.hyperLowerBounds(), hi = model.hyperUpperBounds();
  int adam_t = 0, adam_tz = 0;
  const std::size_t nlat = model.latents().size();
  std::vector<Eigen::MatrixXd> zm(nlat), zv(nlat);
  for (std::size_t k = 0; k < nlat; ++k)
    zm[k] = zv[k] = Eigen::MatrixXd::Zero(model.latents()[k].Z.rows(), model.latents()[k].Z.cols());
  auto schedule = [&](double a, double b, int it) {
    if (cfg.decay_steps <= 0 || it >= cfg.decay_steps) return b;
    return a + (b - a) * static_cast<double>(it) / cfg.decay_steps;  // linear decay (§4.2.5)
  };
  const Eigen::Index per_epoch = (n + B - 1) / B;
  // Decay after the linear phase (TrainConfig::step_decay): 1/√k or step decay on a stalled epoch ELBO.
  const double tau = cfg.decay_tau > 0 ? cfg.decay_tau : static_cast<double>(per_epoch);
  double plateau_scale = 1.0;
  auto decay = [&](int it) {
    switch (cfg.step_decay) {
      case TrainConfig::StepDecay::InvSqrt:
        return it <= cfg.decay_steps ? 1.0 : 1.0 / std::sqrt(1.0 + (it - cfg.decay_steps) / tau);
      case TrainConfig::StepDecay::Plateau:
        return plateau_scale;
      case TrainConfig::StepDecay::Constant:
        break;
    }
    return 1.0;
  };
  double best_epoch = -std::numeric_limits<double>::infinity();
  int calm_epochs = 0;
  // Tail averaging (TrainConfig::average_iterates): sums over the current and the previous epoch.
  IterateSum avg_cur, avg_prev;

  // Mixed precision for this training only (restored on every return path below by the guard).
  struct PrecisionGuard {
    SvgpModel& m;
    bool saved;
    ~PrecisionGuard() { m.setMixedPrecision(saved); }
  } precision_guard{model, model.mixedPrecision()};
  model.setMixedPrecision(cfg.mixed_precision);
  SvgpModel last_good = model;
  double epoch_sum = 0;
  Eigen::Index epoch_count = 0;
  // An epoch is one shuffled partition of the data into per_epoch = ⌈n/B⌉ mini-batches of ⌊n/per_epoch⌋ or
  // ⌈n/per_epoch⌉ points (≤ B), so every point is seen exactly once per epoch and the epoch's summed expected
  // log-likelihood is the full-data one (up to the parameter changes within the epoch), not a sample of it.
  Eigen::MatrixXd Xb;
  Eigen::VectorXd yb;
  double epoch_ell = 0, epoch_kl = 0;
  for (int it = 0; it < cfg.max_iterations; ++it) {
    const Eigen::Index bi = epoch_count;  // batch index within the epoch
    if (bi == 0) std::shuffle(perm.begin(), perm.end(), rng);
    const Eigen::Index b0 = bi * n / per_epoch, b1 = (bi + 1) * n / per_epoch;
    Xb.resize(b1 - b0, X.cols());
    yb.resize(b1 - b0);
    for (Eigen::Index i = b0; i < b1; ++i) {
      Xb.row(i - b0) = X.row(perm[static_cast<std::size_t>(i)]);
      yb[i - b0] = y[perm[static_cast<std::size_t>(i)]];
    }
    const double scale = static_cast<double>(n) / static_cast<double>(b1 - b0);
    const bool hyper = cfg.train_hyper && it >= cfg.hyper_warmup && np > 0 &&
                       (it - cfg.hyper_warmup) % std::max(1, cfg.hyper_every) == 0;
    const bool zstep = cfg.train_inducing && it >= cfg.hyper_warmup &&
                       (it - cfg.hyper_warmup) % std::max(1, cfg.hyper_every) == 0;
    ElboEvaluation ev;
    try {
      ev = model.evaluate(Xb, yb, scale, hyper, zstep);
    } catch (const std::exception& e) {
      model = last_good;
      rep.diverged = true;
      rep.message = std::string("numerical failure (") + e.what() + "); kept the last good model";
      break;
    }
    bool zfinite = true;
    for (const auto& g : ev.z_grad) zfinite = zfinite && g.allFinite();
    if (!std::isfinite(ev.elbo) || (hyper && !ev.hyper_grad.allFinite()) || !zfinite) {
      model = last_good;
      rep.diverged = true;
      rep.message = "ELBO became NaN/Inf at iteration " + std::to_string(it) + "; kept the last good model";
      break;
    }
    last_good = model;
    // Natural-gradient step on q(u_f), q(u_g) ...
    const double gamma = schedule(cfg.natgrad_gamma_start, cfg.natgrad_gamma_end, it) * decay(it);
    rep.final_gamma = gamma;
    for (int k = 0; k < static_cast<int>(model.latents().size()); ++k) model.naturalGradientStep(k, ev, scale, gamma);
    // ... then Adam on the kernel hyperparameters (§4.2.5).
    if (hyper) {
      ++adam_t;
      const double lr = schedule(cfg.adam_lr_start, cfg.adam_lr_end, it - cfg.hyper_warmup) * decay(it);
      const Eigen::VectorXd g = -ev.hyper_grad / static_cast<double>(n);  // per-point loss gradient
      am = 0.9 * am + 0.1 * g;
      av = 0.999 * av + 0.001 * g.cwiseProduct(g);
      const double c1 = 1.0 - std::pow(0.9, adam_t), c2 = 1.0 - std::pow(0.999, adam_t);
      Eigen::VectorXd p = model.hyperParams();
      p.array() -= lr * (am.array() / c1) / ((av.array() / c2).sqrt() + 1e-8);
      model.setHyperParams(p.cwiseMax(lo).cwiseMin(hi));
    }
    if (zstep) {
      ++adam_tz;
      const double c1 = 1.0 - std::pow(0.9, adam_tz), c2 = 1.0 - std::pow(0.999, adam_tz);
      for (std::size_t k = 0; k < nlat; ++k) {
        const Eigen::MatrixXd g = -ev.z_grad[k] / static_cast<double>(n);
        zm[k] = 0.9 * zm[k] + 0.1 * g;
        zv[k] = 0.999 * zv[k] + 0.001 * g.cwiseProduct(g);
        model.latents()[k].Z.array() -= cfg.inducing_lr * (zm[k].array() / c1) / ((zv[k].array() / c2).sqrt() + 1e-8);
      }
    }
    ++rep.iterations;
    if (cfg.average_iterates && it >= cfg.decay_steps) avg_cur.add(model);
    const double per_point = ev.elbo / static_cast<double>(n);
    if (cfg.progress) cfg.progress(it, per_point, elapsed());
    epoch_sum += per_point;
    epoch_ell += ev.ell;
    epoch_kl += ev.kl;
    ++epoch_count;
    if (epoch_count == per_epoch) {
      // Σ_batches E[log p] over the partition minus the mean KL, per point: the full-data ELBO (eq. 4.12).
      const double mean = (epoch_ell - epoch_kl / static_cast<double>(per_epoch)) / static_cast<double>(n);
      rep.epoch_elbo.push_back(mean);
      ++rep.epochs;
      epoch_sum = 0;
      epoch_count = 0;
      epoch_ell = epoch_kl = 0;
      if (avg_cur.count > 0) {
        avg_prev = std::move(avg_cur);
        avg_cur = IterateSum();
      }
      const std::size_t e = rep.epoch_elbo.size();
      if (cfg.on_epoch) cfg.on_epoch(static_cast<int>(e), mean);
      if (cfg.step_decay == TrainConfig::StepDecay::Plateau && mean < best_epoch)
        plateau_scale *= cfg.plateau_factor;
      best_epoch = std::max(best_epoch, mean);
      if (static_cast<int>(e) >= cfg.min_epochs && e >= 2) {
        const double prev = rep.epoch_elbo[e - 2];
        const double ref = std::max({1e-12, std::abs(prev), cfg.elbo_floor});
        calm_epochs = std::abs(mean - prev) <= cfg.tolerance * ref ? calm_epochs + 1 : 0;
        if (calm_epochs >= std::max(1, cfg.patience)) {
          rep.converged = true;
          rep.message = "converged: epoch ELBO change below tolerance in " + std::to_string(calm_epochs) +
                        " consecutive epoch(s)";
          break;
        }
      }
    }
    if (elapsed() > cfg.max_seconds) {
      rep.message = "stopped at the time limit";
      break;
    }
  }
  if (rep.message.empty()) rep.message = "stopped at the iteration limit";
  if (!rep.diverged && avg_prev.count + avg_cur.count > 0) {
    avg_prev.merge(avg_cur);
    rep.averaged_iterates = avg_prev.count;
    if (!avg_prev.apply(model)) {
      rep.averaged_iterates = 0;
      rep.message += "; iterate average not positive definite, kept the last iterate";
    }
  }
  rep.final_elbo = rep.epoch_elbo.empty() ? (epoch_count ? epoch_sum / epoch_count : 0.0) : rep.epoch_elbo.back();
  rep.seconds = elapsed();
  return rep;
}

}  // namespace cairn::copa_map
