// Heap-allocation counter for no-allocation tests (Drake's LimitMalloc idea): replaces the global
// operator new / delete of the test executable that includes it (include it in ONE file per
// executable). Set g_count_allocs, run the code under test, read g_allocs.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC cannot see that the replaced operator new pairs with the replaced operator delete below.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
namespace dentsim::testing {
inline std::atomic<bool> g_count_allocs{false};
inline std::atomic<long> g_allocs{0};
}  // namespace dentsim::testing

void* operator new(std::size_t n) {
  if (dentsim::testing::g_count_allocs.load(std::memory_order_relaxed)) {
    dentsim::testing::g_allocs.fetch_add(1);
  }
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
