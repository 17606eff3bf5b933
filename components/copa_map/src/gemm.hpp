// Internal: run-time dispatched dense matrix product for the O(B m²) and O(m³) products of SVGP training.
#pragma once

namespace cairn::copa_map::detail {

// C (M x N, leading dimension ldc) = alpha op(A) op(B) + beta C, column-major; op = transpose when trans_*.
struct GemmArgs {
  bool trans_a, trans_b;
  long M, N, K;
  double alpha;
  const double* A;
  long lda;
  const double* B;
  long ldb;
  double beta;
  double* C;
  long ldc;
};

// The variant chosen at run time (cpu_dispatch.hpp).
void gemm(const GemmArgs& g);

void gemm_generic(const GemmArgs& g);
#if defined(CAIRN_COPA_HAVE_X86_VARIANTS)
void gemm_avx2(const GemmArgs& g);
void gemm_avx512(const GemmArgs& g);
#endif

}  // namespace cairn::copa_map::detail
