// Internal: run-time dispatched dense matrix product for the O(B m²) and O(m³) products of SVGP training.
#pragma once

namespace cairn::copa_map::detail {

// C (M x N, leading dimension ldc) = alpha op(A) op(B) + beta C, column-major; op = transpose when trans_*.
template <class T>
struct GemmArgsT {
  bool trans_a, trans_b;
  long M, N, K;
  T alpha;
  const T* A;
  long lda;
  const T* B;
  long ldb;
  T beta;
  T* C;
  long ldc;
};
using GemmArgs = GemmArgsT<double>;
using GemmArgsF = GemmArgsT<float>;  // single precision: the mixed-precision B·m² products (svgp.cpp)

// The variant chosen at run time (cpu_dispatch.hpp).
void gemm(const GemmArgs& g);
void gemm(const GemmArgsF& g);

void gemm_generic(const GemmArgs& g);
void gemm_generic(const GemmArgsF& g);
#if defined(CAIRN_COPA_HAVE_X86_VARIANTS)
void gemm_avx2(const GemmArgs& g);
void gemm_avx2(const GemmArgsF& g);
void gemm_avx512(const GemmArgs& g);
void gemm_avx512(const GemmArgsF& g);
#endif

}  // namespace cairn::copa_map::detail
