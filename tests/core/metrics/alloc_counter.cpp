#include "alloc_counter.hpp"

#include <cstdlib>
#include <new>

void* operator new(std::size_t n) {
  if (vitreo::core::test::AllocationCounter::counting) ++vitreo::core::test::AllocationCounter::allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
