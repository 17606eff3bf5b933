// One dense GEMM, C = alpha op(A) op(B) + beta C (column-major, raw pointers), compiled once per instruction set
// (see CMakeLists.txt: generic = the build's flags, avx2 = -mavx2 -mfma, avx512 = -mavx512f …) and chosen at run
// time by gemm_dispatch.cpp. 75 % of a CoPA-Map training step at m = 1,915 is Eigen's GEMM kernel (perf,
// docs/benchmarks.md), which Eigen vectorizes only for the instruction set it is compiled for.
//
// Each variant includes its own copy of Eigen in a renamed namespace (the macro below), so the variants' template
// instantiations (gebp_kernel, pack functions, …) have different symbol names and the linker cannot merge an
// AVX-512 copy into code that runs on an SSE2-only CPU. Only raw pointers cross this file's interface.
#ifndef CAIRN_GEMM_VARIANT
#error "CAIRN_GEMM_VARIANT (generic, avx2, avx512) must be defined"
#endif
#define CAIRN_GEMM_CAT2(a, b) a##b
#define CAIRN_GEMM_CAT(a, b) CAIRN_GEMM_CAT2(a, b)
#define Eigen CAIRN_GEMM_CAT(cairn_copa_eigen_, CAIRN_GEMM_VARIANT)
#include <Eigen/Core>

#include "gemm.hpp"

namespace cairn::copa_map::detail {
namespace {

template <class T>
using Mat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
using Stride = Eigen::OuterStride<>;

template <class OA, class OB, class MapC, class T>
void run(MapC& C, const OA& a, const OB& b, T alpha, T beta) {
  if (beta == T(0)) {
    C.noalias() = alpha * a * b;
  } else {
    if (beta != T(1)) C *= beta;
    C.noalias() += alpha * a * b;
  }
}

template <class T>
void gemmT(const GemmArgsT<T>& g) {
  using ConstMap = Eigen::Map<const Mat<T>, 0, Stride>;
  Eigen::Map<Mat<T>, 0, Stride> C(g.C, g.M, g.N, Stride(g.ldc));
  const ConstMap A(g.A, g.trans_a ? g.K : g.M, g.trans_a ? g.M : g.K, Stride(g.lda));
  const ConstMap B(g.B, g.trans_b ? g.N : g.K, g.trans_b ? g.K : g.N, Stride(g.ldb));
  if (!g.trans_a && !g.trans_b) run(C, A, B, g.alpha, g.beta);
  else if (g.trans_a && !g.trans_b) run(C, A.transpose(), B, g.alpha, g.beta);
  else if (!g.trans_a && g.trans_b) run(C, A, B.transpose(), g.alpha, g.beta);
  else run(C, A.transpose(), B.transpose(), g.alpha, g.beta);
}

}  // namespace

void CAIRN_GEMM_CAT(gemm_, CAIRN_GEMM_VARIANT)(const GemmArgs& g) { gemmT(g); }
void CAIRN_GEMM_CAT(gemm_, CAIRN_GEMM_VARIANT)(const GemmArgsF& g) { gemmT(g); }

}  // namespace cairn::copa_map::detail
