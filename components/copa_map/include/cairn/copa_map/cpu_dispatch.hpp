// Run-time choice of the instruction set for CoPA-Map's dense matrix products (SVGP training and prediction).
// The library is built portably (the build's flags, e.g. SSE2 on x86-64) and additionally carries AVX2+FMA and
// AVX-512 copies of its GEMM on x86-64; the best one the CPU supports is used unless the environment variable
// CAIRN_COPA_GEMM (generic, avx2, avx512) or selectGemmKernel() says otherwise.
#pragma once

#include <string>
#include <vector>

namespace cairn::copa_map {

// Name of the GEMM variant in use ("generic", "avx2" or "avx512").
std::string activeGemmKernel();
// Variants this build has and this CPU can run, best last.
std::vector<std::string> availableGemmKernels();
// Switch to `name` (for benchmarks and tests: before/after in one run). Throws std::invalid_argument for an
// unknown name or one the CPU cannot run. Not meant to be called while another thread trains or predicts.
void selectGemmKernel(const std::string& name);

}  // namespace cairn::copa_map
