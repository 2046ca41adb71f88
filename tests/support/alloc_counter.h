// Heap-allocation counter for the no-allocation tests (Drake's LimitMalloc idea). Include it in
// exactly one file of a test executable: it replaces the global operator new/delete and, outside
// the sanitizer build, malloc itself, since Eigen's dynamic matrices call std::malloc directly
// (glibc's __libc_malloc does the work; ASan intercepts malloc, so there only operator new is
// counted: kCountsMalloc says which). Usage: g_allocs = 0; g_count_allocs = true; ...;
// g_count_allocs = false; EXPECT_EQ(g_allocs.load(), 0).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC cannot see that the replaced operator new pairs with the replaced operator delete below.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

inline std::atomic<bool> g_count_allocs{false};
inline std::atomic<long> g_allocs{0};

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kCountsMalloc = false;
#else
inline constexpr bool kCountsMalloc = true;
extern "C" void* __libc_malloc(std::size_t n);
extern "C" void* malloc(std::size_t n) noexcept {
  if (g_count_allocs.load(std::memory_order_relaxed)) g_allocs.fetch_add(1);
  return __libc_malloc(n);
}
#endif

void* operator new(std::size_t n) {
  if (g_count_allocs.load(std::memory_order_relaxed)) g_allocs.fetch_add(1);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
