#include "reference/core/setup_threads.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "reference/core/io.h"

namespace dentsim {

int setup_threads() {
  if (const char* v = std::getenv("DENTSIM_SETUP_THREADS"); v != nullptr) {
    const std::string s(v);
    const bool digits = !s.empty() && s.size() <= 4 &&
                        std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
    const int n = digits ? std::stoi(s) : 0;
    if (n < 1 || n > 1024) {
      throw InputError("DENTSIM_SETUP_THREADS: expected a whole number from 1 to 1024, got '" + s +
                       "'");
    }
    return n;
  }
  const unsigned hw = std::thread::hardware_concurrency();
  return std::clamp(static_cast<int>(hw), 1, kMaxSetupThreads);
}

void parallel_tasks(int count, int threads, const std::function<void(int)>& task) {
  if (threads <= 0) threads = setup_threads();
  threads = std::min(threads, count);
  if (threads <= 1) {
    for (int i = 0; i < count; ++i) task(i);
    return;
  }
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto work = [&] {
    try {
      for (int i = next.fetch_add(1); i < count; i = next.fetch_add(1)) task(i);
    } catch (...) {
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next.store(count);  // the others stop at their next task
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace dentsim
