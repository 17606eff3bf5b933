// Global operator new/delete that count heap allocations of the calling thread while armed.
#include <cstdlib>
#include <new>

thread_local bool g_count_allocs = false;
thread_local long g_allocs = 0;

void* operator new(std::size_t n) {
  if (g_count_allocs) ++g_allocs;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
