// Sweeps spread over MPI ranks (issue #20; docs/scaling.md). `mpirun -n N dentsim zwidth ...`
// (and `dentsim bench`, `dentsim calibrate-seeds`) give each rank a share of the independent jobs
// of a sweep (grid points, variants, seeds) and gather the results on rank 0, which writes the one
// JSON: identical to what a single process writes. Without mpirun, or in a build without MPI
// (DENTSIM_MPI=OFF or OpenMPI not found), there is one rank and everything runs here as before.
//
// MPI lives only in the CLI: the libraries (and the Python module) never see it.
//
// Launching: MPI is initialised only when the environment shows an MPI launcher (mpirun/mpiexec
// of Open MPI or MPICH, `srun --mpi=pmix|pmi2`), so the plain `dentsim ...` never pays MPI_Init.
// A command that is not a sweep (`dentsim run`, `replay`, ...) refuses to start under a launcher
// with more than one rank (exit status 2, the message on rank 0 only): N copies would run the same
// scene and write the same files. So does every command of a build without MPI: each copy would
// believe it is alone and run the whole sweep.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace dentsim::cli {

// This process's place in the job: rank 0 of 1 unless started by an MPI launcher.
struct SweepWorld {
  int rank = 0;
  int size = 1;
  bool mpi = false;  // true when MPI was initialised (launched by mpirun/srun in an MPI build)
};

// The world, MPI initialised on the first call when the process was launched by an MPI launcher
// (MPI is finalised at exit). Cheap afterwards.
const SweepWorld& sweep_world();

// Runs job(i) for each i in [0, n) owned by this rank (i % size == rank, so the cost of a grid
// ordered by difficulty spreads evenly), then gathers every job's JSON on rank 0. Returns the n
// results in index order on rank 0 and an empty vector on the other ranks. A job that throws on
// any rank makes every rank throw dentsim::InputError / std::runtime_error with the first failing
// job's message (the lowest failing index; rank 0 prints it, as for a single process) — no rank
// is left waiting. A rank stops running its jobs after its first failure.
// `on_done(done, owned)` (optional) is called on rank 0 as its own jobs finish, for progress
// output: `done` of its `owned` jobs (owned = n on one rank); calls are serialised.
// Every result goes through dump() and parse() on one rank as on many, so the results never depend
// on the number of ranks: doubles round-trip exactly, but JSON has no NaN or infinity (dump writes
// null) — a job that can produce them encodes them itself (e.g. as strings).
std::vector<nlohmann::json> sweep(int n, const std::function<nlohmann::json(int)>& job,
                                  const std::function<void(int, int)>& on_done = {});

struct SweepOptions {
  // std::threads per rank running that rank's jobs (>= 1; job must then be thread-safe). With
  // one thread the jobs run in index order.
  int threads = 1;
  // true: every rank gets the n results (rank 0 broadcasts them), for sweeps whose next stage
  // every rank has to enumerate (zwidth's re-runs at each method's best grid point).
  bool results_on_every_rank = false;
};
std::vector<nlohmann::json> sweep(int n, const std::function<nlohmann::json(int)>& job,
                                  const std::function<void(int, int)>& on_done,
                                  const SweepOptions& options);

// True on the rank that writes the outputs (rank 0).
inline bool writes_outputs() { return sweep_world().rank == 0; }

// The rank an MPI launcher gave this process, read from its environment without initialising MPI
// (0 without a launcher): main prints errors on rank 0 only.
int launcher_rank();

// What `dentsim info` says of MPI: "yes (<library, first line>; launcher <mpiexec>)" in an MPI
// build, "no (sweeps run in one process)" without. Safe before MPI is initialised.
std::string mpi_build_description();

}  // namespace dentsim::cli
