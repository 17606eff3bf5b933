// Global operator new/delete that count heap allocations of the calling thread while armed.
#include "alloc_counter.hpp"

#include <cstdlib>
#include <new>

namespace {
thread_local bool t_counting = false;
thread_local long t_allocs = 0;
}  // namespace

void start_counting_allocations() {
  t_allocs = 0;
  t_counting = true;
}

long stop_counting_allocations() {
  t_counting = false;
  return t_allocs;
}

void* operator new(std::size_t n) {
  if (t_counting) ++t_allocs;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
// The nothrow forms too (std::stable_partition's temporary buffer uses them): they are counted like the others,
// and left to the sanitizer's or the library's own they allocated with its operator new while the replaced
// operator delete below freed with free() (AddressSanitizer: alloc-dealloc-mismatch).
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  if (t_counting) ++t_allocs;
  return std::malloc(n ? n : 1);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
