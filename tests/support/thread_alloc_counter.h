// Heap-allocation counter for the threads that switch it on (the vendor's scheduler thread, from
// inside its callback: tests/device/hdapi_device_test.cc, tests/device/callback_loop_test.cc).
// Like tests/support/alloc_counter.h, which counts every thread, it replaces the test
// executable's operator new/delete and, outside the sanitizer build, malloc itself (Eigen's
// dynamic matrices call std::malloc; ASan intercepts malloc, so there only operator new is
// counted). Include it in ONE translation unit of a test executable.
//
//   dentsim::testing::t_count_thread_allocs = true;   // on the thread to watch
//   ... dentsim::testing::g_thread_allocs.load() ...  // allocations counted so far
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

// GCC cannot see that the replaced operator new pairs with the replaced operator delete below.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace dentsim::testing {
inline thread_local bool t_count_thread_allocs = false;
inline std::atomic<long> g_thread_allocs{0};
inline void count_thread_allocation() {
  if (t_count_thread_allocs) g_thread_allocs.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace dentsim::testing

#if !defined(__SANITIZE_ADDRESS__)
extern "C" void* __libc_malloc(std::size_t n);
extern "C" void* malloc(std::size_t n) noexcept {
  dentsim::testing::count_thread_allocation();
  return __libc_malloc(n);
}
#endif

void* operator new(std::size_t n) {
#if defined(__SANITIZE_ADDRESS__)
  dentsim::testing::count_thread_allocation();  // else malloc counts it
#endif
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
