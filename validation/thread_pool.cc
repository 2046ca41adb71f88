#include "validation/thread_pool.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace dentsim {

void run_jobs_on_threads(int n, int threads, const std::function<void(int)>& job,
                         const std::function<void(int, int)>& progress, int* failed_index) {
  std::atomic<int> next{0};
  std::mutex mu;
  int done = 0;
  int failed = -1;
  std::exception_ptr error;
  auto worker = [&] {
    for (;;) {
      const int i = next.fetch_add(1);
      if (i >= n) return;
      try {
        job(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        if (failed < 0 || i < failed) {
          failed = i;
          error = std::current_exception();
        }
        next.store(n);
        return;
      }
      std::lock_guard<std::mutex> lock(mu);
      ++done;
      if (progress) progress(done, n);
    }
  };
  const int nt = std::clamp(threads, 1, std::max(1, n));
  std::vector<std::thread> pool;
  for (int t = 0; t < nt; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  if (failed_index != nullptr) *failed_index = failed;
  if (error) std::rethrow_exception(error);
}

}  // namespace dentsim
