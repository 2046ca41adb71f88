// The one thread pool of dentsim's sweeps (the Z-width sweeps and experiment runner,
// validation/zwidth.h and zwidth_experiment.h; the MPI sweeps' jobs per rank, cli/mpi_sweep.h).
#pragma once

#include <functional>

namespace dentsim {

// Runs job(0), ..., job(n - 1) on `threads` std::threads (at most n); `progress(done, n)` is
// called (serialised) after every job that returned. A job that throws stops new jobs from
// starting; the exception of the lowest failing index is rethrown once all threads are done,
// with that index in *failed_index when given (-1 when every job returned).
void run_jobs_on_threads(int n, int threads, const std::function<void(int)>& job,
                         const std::function<void(int, int)>& progress = {},
                         int* failed_index = nullptr);

}  // namespace dentsim
