// Heap-allocation counter for the no-allocation tests (Drake's LimitMalloc idea): replaces the
// global operator new/delete of the test executable and, outside the sanitizer build, malloc
// itself, since Eigen's dynamic matrices call std::malloc directly (glibc's __libc_malloc does the
// work; ASan and TSan intercept malloc, so there only operator new is counted: kCountsMalloc says
// which).
// Include it in ONE translation unit of a test executable (each tests/<area>/<name>_test.cc is its
// own executable).
//
//   {
//     dentsim::testing::AllocationScope scope;   // counts from here ...
//     ... code under test ...
//     EXPECT_EQ(scope.count(), 0);                // ... to here
//   }
// or by hand: g_allocs = 0; g_count_allocs = true; ...; g_count_allocs = false.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC cannot see that the replaced operator new pairs with the replaced operator delete below.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace dentsim::testing {
inline std::atomic<bool> g_count_allocs{false};
inline std::atomic<long> g_allocs{0};

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kCountsMalloc = false;
#else
inline constexpr bool kCountsMalloc = true;
#endif

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

using dentsim::testing::g_allocs;
using dentsim::testing::g_count_allocs;
using dentsim::testing::kCountsMalloc;

#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
extern "C" void* __libc_malloc(std::size_t n);
extern "C" void* malloc(std::size_t n) noexcept {
  if (dentsim::testing::g_count_allocs.load(std::memory_order_relaxed)) {
    dentsim::testing::g_allocs.fetch_add(1);
  }
  return __libc_malloc(n);
}
#endif

inline void count_allocation() {
  if (dentsim::testing::g_count_allocs.load(std::memory_order_relaxed)) {
    dentsim::testing::g_allocs.fetch_add(1);
  }
}

void* operator new(std::size_t n) {
  if (!dentsim::testing::kCountsMalloc) count_allocation();  // else malloc counts it
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t a) {
  count_allocation();  // aligned_alloc is not the malloc above
  const std::size_t al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
