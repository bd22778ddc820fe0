#include "counting_new.hpp"  // NOLINT(build/include_subdir)

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace drivetrain_stiffness::test {
long allocationCount() { return g_allocations.load(); }
}  // namespace drivetrain_stiffness::test
