// Allocation counter for the no-allocation-per-tick tests (Drake's LimitMalloc idea): replaces the
// global operator new/delete of the test executable. Include it in ONE translation unit of a test
// executable (each tests/<area>/<name>_test.cc is its own executable).
//
//   {
//     dentsim::testing::AllocationScope scope;   // counts from here ...
//     ... code under test ...
//     EXPECT_EQ(scope.count(), 0);                // ... to here
//   }
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC cannot see that the replaced operator new pairs with the replaced operator delete below.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace dentsim::testing {
inline std::atomic<bool> g_count_allocs{false};
inline std::atomic<long> g_allocs{0};

class AllocationScope {
 public:
  AllocationScope() {
    g_allocs.store(0);
    g_count_allocs.store(true);
  }
  ~AllocationScope() { g_count_allocs.store(false); }
  AllocationScope(const AllocationScope&) = delete;
  AllocationScope& operator=(const AllocationScope&) = delete;
  long count() const { return g_allocs.load(); }
};
}  // namespace dentsim::testing

void* operator new(std::size_t n) {
  if (dentsim::testing::g_count_allocs.load(std::memory_order_relaxed)) {
    dentsim::testing::g_allocs.fetch_add(1);
  }
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t a) {
  if (dentsim::testing::g_count_allocs.load(std::memory_order_relaxed)) {
    dentsim::testing::g_allocs.fetch_add(1);
  }
  const std::size_t al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
