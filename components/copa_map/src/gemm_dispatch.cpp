#include <atomic>
#include <cstdlib>
#include <stdexcept>

#include "cairn/copa_map/cpu_dispatch.hpp"
#include "gemm.hpp"

namespace cairn::copa_map {
namespace detail {
namespace {

using Fn = void (*)(const GemmArgs&);
using FnF = void (*)(const GemmArgsF&);
struct Variant {
  const char* name;
  Fn fn;
  FnF fnf;
  bool (*supported)();
};

#if defined(CAIRN_COPA_HAVE_X86_VARIANTS)
bool hasAvx2() { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }
bool hasAvx512() {
  return hasAvx2() && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
         __builtin_cpu_supports("avx512dq");
}
#endif
bool always() { return true; }

const Variant kVariants[] = {
    {"generic", &gemm_generic, &gemm_generic, &always},
#if defined(CAIRN_COPA_HAVE_X86_VARIANTS)
    {"avx2", &gemm_avx2, &gemm_avx2, &hasAvx2},
    {"avx512", &gemm_avx512, &gemm_avx512, &hasAvx512},
#endif
};

const Variant* find(const std::string& name) {
  for (const auto& v : kVariants)
    if (name == v.name) return &v;
  return nullptr;
}

const Variant* best() {
  if (const char* env = std::getenv("CAIRN_COPA_GEMM")) {
    const Variant* v = find(env);
    if (v && v->supported()) return v;  // an unusable override falls back to the best supported variant
  }
  const Variant* b = &kVariants[0];
  for (const auto& v : kVariants)
    if (v.supported()) b = &v;
  return b;
}

std::atomic<const Variant*>& current() {
  static std::atomic<const Variant*> c{best()};
  return c;
}

}  // namespace

void gemm(const GemmArgs& g) {
  if (g.M == 0 || g.N == 0) return;
  current().load(std::memory_order_relaxed)->fn(g);
}

void gemm(const GemmArgsF& g) {
  if (g.M == 0 || g.N == 0) return;
  current().load(std::memory_order_relaxed)->fnf(g);
}

}  // namespace detail

std::string activeGemmKernel() { return detail::current().load()->name; }

std::vector<std::string> availableGemmKernels() {
  std::vector<std::string> out;
  for (const auto& v : detail::kVariants)
    if (v.supported()) out.emplace_back(v.name);
  return out;
}

void selectGemmKernel(const std::string& name) {
  const detail::Variant* v = detail::find(name);
  if (!v) throw std::invalid_argument("selectGemmKernel: unknown GEMM variant '" + name + "'");
  if (!v->supported()) throw std::invalid_argument("selectGemmKernel: this CPU cannot run '" + name + "'");
  detail::current().store(v);
}

}  // namespace cairn::copa_map
