#include "validation/thread_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

namespace dentsim {
namespace {

TEST(ThreadPool, RunsEveryJobOnceAndReportsProgressInOrder) {
  for (int threads : {1, 2, 7}) {
    std::vector<std::atomic<int>> runs(50);
    std::vector<int> seen;
    int failed = 123;
    run_jobs_on_threads(
        50, threads, [&](int i) { runs[static_cast<std::size_t>(i)].fetch_add(1); },
        [&](int done, int n) {
          EXPECT_EQ(n, 50);
          seen.push_back(done);
        },
        &failed);
    for (const auto& r : runs) EXPECT_EQ(r.load(), 1);
    ASSERT_EQ(seen.size(), 50u);
    for (std::size_t k = 0; k < seen.size(); ++k) EXPECT_EQ(seen[k], static_cast<int>(k) + 1);
    EXPECT_EQ(failed, -1);
  }
}

TEST(ThreadPool, RethrowsTheLowestFailingIndexAndStopsNewJobs) {
  // One thread takes the jobs in order: jobs after the first failure never start.
  std::atomic<int> started{0};
  int failed = -1;
  try {
    run_jobs_on_threads(
        20, 1,
        [&](int i) {
          started.fetch_add(1);
          if (i == 4 || i == 9) throw std::runtime_error("job " + std::to_string(i));
        },
        {}, &failed);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "job 4");
  }
  EXPECT_EQ(failed, 4);
  EXPECT_EQ(started.load(), 5);
  // Many threads: whichever ran first, the lowest failing index wins.
  for (int rep = 0; rep < 20; ++rep) {
    try {
      run_jobs_on_threads(8, 8, [&](int i) {
        if (i % 3 == 2) throw std::runtime_error("job " + std::to_string(i));
      }, {}, &failed);
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      // Job 2 always starts (8 threads, 8 jobs) and fails; nothing below it fails.
      EXPECT_STREQ(e.what(), "job 2");
      EXPECT_EQ(failed, 2);
    }
  }
}

}  // namespace
}  // namespace dentsim
