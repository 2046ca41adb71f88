// Sweeps over MPI ranks (cli/mpi_sweep.h, docs/scaling.md).
//
// Protocol of one sweep (every rank takes every step, so no rank can be left waiting):
//   1. each rank runs its jobs (i % size == rank) on its threads and packs one JSON document
//      {"failure": null | {"index", "input", "message"}, "results": [...]} (its failure, if any,
//      is the lowest index that threw);
//   2. MPI_Gather of the packed lengths to rank 0, which checks that they fit MPI's int counts and
//      broadcasts go / no-go; MPI_Gatherv of the packed bytes;
//   3. rank 0 unpacks, picks the failure with the lowest job index, and broadcasts the outcome:
//      the failure, or the results (results_on_every_rank), or just "ok";
//   4. every rank throws the failure (InputError when the job threw one: exit status 2) or
//      returns.
// One rank (no launcher, or a build without MPI) takes step 1 only, with the same packing, so a
// result never depends on the number of ranks.
#include "cli/mpi_sweep.h"

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cli/registry.h"
#include "reference/core/io.h"
#include "validation/thread_pool.h"

#ifdef DENTSIM_HAVE_MPI
// The C API only: Open MPI's and MPICH's mpi.h otherwise pull in the deprecated C++ bindings,
// which need libmpi_cxx.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace dentsim::cli {
namespace {

// An integer from the environment (nullopt when unset or not a number).
std::optional<int> env_int(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return std::nullopt;
  char* end = nullptr;
  const long x = std::strtol(v, &end, 10);
  if (*end != '\0' || x < 0 || x > INT_MAX) return std::nullopt;
  return static_cast<int>(x);
}

// The variables MPI launchers set in each process they start: Open MPI's mpirun
// (OMPI_COMM_WORLD_*), MPICH's Hydra and Slurm's `srun --mpi=pmi2` (PMI_*), PMIx launchers such as
// `srun --mpi=pmix` (PMIX_RANK). Slurm's own SLURM_PROCID is not one: a batch script has it too,
// outside any step.
bool launched() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMI_RANK", "PMIX_RANK"}) {
    if (std::getenv(v) != nullptr) return true;
  }
  return false;
}

// The number of processes the launcher started (1 without a launcher or when it does not say).
int launcher_size() {
  if (!launched()) return 1;
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "SLURM_STEP_NUM_TASKS"}) {
    if (const auto n = env_int(v)) return std::max(1, *n);
  }
  return 1;
}

#ifdef DENTSIM_HAVE_MPI
void finalize_mpi() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}
#endif

SweepWorld make_world() {
  SweepWorld w;
#ifdef DENTSIM_HAVE_MPI
  if (!launched()) return w;
  // Worker threads only compute; MPI is called from the main thread alone.
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  std::atexit(finalize_mpi);
  MPI_Comm_rank(MPI_COMM_WORLD, &w.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &w.size);
  w.mpi = true;
#endif
  return w;
}

// A job's failure: the lowest failing index of a rank (or of all ranks).
struct Failure {
  int index = -1;
  bool input = false;  // the job threw InputError (bad input: exit status 2)
  std::string message;
};

#ifdef DENTSIM_HAVE_MPI
nlohmann::json failure_json(const std::optional<Failure>& f) {
  if (!f) return nullptr;
  return {{"index", f->index}, {"input", f->input}, {"message", f->message}};
}

std::optional<Failure> failure_from(const nlohmann::json& j) {
  if (j.is_null()) return std::nullopt;
  return Failure{j.at("index").get<int>(), j.at("input").get<bool>(),
                 j.at("message").get<std::string>()};
}
#endif

[[noreturn]] void raise(const Failure& f) {
  if (f.input) throw InputError(f.message);
  throw std::runtime_error(f.message);
}

// Runs job(owned[k]) for every k on `threads` threads (validation/thread_pool.h). Returns the
// dumped results in the order of `owned` (those after a failure left empty) and the failure with
// the lowest index, if any.
std::vector<std::string> run_owned(const std::vector<int>& owned,
                                   const std::function<nlohmann::json(int)>& job,
                                   const std::function<void(int, int)>& on_done, int threads,
                                   std::optional<Failure>* failure) {
  std::vector<std::string> out(owned.size());
  int failed = -1;
  try {
    run_jobs_on_threads(
        static_cast<int>(owned.size()), threads,
        [&](int k) { out[static_cast<std::size_t>(k)] = job(owned[k]).dump(); }, on_done, &failed);
  } catch (const InputError& e) {
    *failure = Failure{owned[failed], true, e.what()};
  } catch (const std::exception& e) {
    *failure = Failure{owned[failed], false, e.what()};
  } catch (...) {
    *failure = Failure{owned[failed], false,
                       "job " + std::to_string(owned[failed]) + " failed (unknown exception)"};
  }
  return out;
}

#ifdef DENTSIM_HAVE_MPI
// Rank 0's string sent to every rank (length first: the receivers size their buffer).
void broadcast(std::string& s, int rank) {
  unsigned long long len = s.size();
  MPI_Bcast(&len, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  if (rank != 0) s.assign(len, '\0');
  // MPI counts are ints: send in slices of at most 1 GiB.
  constexpr unsigned long long kSlice = 1ull << 30;
  for (unsigned long long at = 0; at < len; at += kSlice) {
    const int count = static_cast<int>(std::min(kSlice, len - at));
    MPI_Bcast(s.data() + at, count, MPI_CHAR, 0, MPI_COMM_WORLD);
  }
}
#endif

}  // namespace

const SweepWorld& sweep_world() {
  static const SweepWorld world = make_world();
  return world;
}

int launcher_rank() {
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"}) {
    if (const auto r = env_int(v)) return *r;
  }
  return 0;
}

std::vector<nlohmann::json> sweep(int n, const std::function<nlohmann::json(int)>& job,
                                  const std::function<void(int, int)>& on_done) {
  return sweep(n, job, on_done, SweepOptions{});
}

std::vector<nlohmann::json> sweep(int n, const std::function<nlohmann::json(int)>& job,
                                  const std::function<void(int, int)>& on_done,
                                  const SweepOptions& options) {
  if (n < 0) throw std::invalid_argument("sweep: negative job count");
  const SweepWorld& w = sweep_world();
  std::vector<int> owned;
  for (int i = w.rank; i < n; i += w.size) owned.push_back(i);
  std::optional<Failure> failure;
  const std::vector<std::string> mine =
      run_owned(owned, job, w.rank == 0 ? on_done : std::function<void(int, int)>{},
                options.threads, &failure);

  if (!w.mpi) {
    if (failure) raise(*failure);
    std::vector<nlohmann::json> results;
    results.reserve(mine.size());
    for (const std::string& s : mine) results.push_back(nlohmann::json::parse(s));
    return results;
  }

#ifdef DENTSIM_HAVE_MPI
  // 1. This rank's package (results as dumped text: parsed once, on rank 0).
  // The results are already JSON text: spliced in as they are, not quoted as strings.
  std::string packed = "{\"failure\":" + failure_json(failure).dump() + ",\"results\":[";
  if (!failure) {
    for (std::size_t k = 0; k < mine.size(); ++k) packed += (k > 0 ? "," : "") + mine[k];
  }
  packed += "]}";
  // 2. Lengths, go / no-go, bytes.
  const unsigned long long my_len = packed.size();
  std::vector<unsigned long long> lens(w.rank == 0 ? w.size : 0);
  MPI_Gather(&my_len, 1, MPI_UNSIGNED_LONG_LONG, lens.data(), 1, MPI_UNSIGNED_LONG_LONG, 0,
             MPI_COMM_WORLD);
  int fits = 1;
  std::vector<int> counts, displs;
  if (w.rank == 0) {
    unsigned long long total = 0;
    for (unsigned long long l : lens) {
      counts.push_back(static_cast<int>(std::min<unsigned long long>(l, INT_MAX)));
      displs.push_back(static_cast<int>(std::min<unsigned long long>(total, INT_MAX)));
      total += l;
    }
    fits = total <= static_cast<unsigned long long>(INT_MAX) ? 1 : 0;
  }
  MPI_Bcast(&fits, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string outcome;
  std::vector<nlohmann::json> results;
  if (!fits) {
    outcome = nlohmann::json{{"failure",
                              {{"index", -1},
                               {"input", false},
                               {"message",
                                "sweep: the gathered results exceed 2 GiB (MPI's int counts); "
                                "split the sweep"}}}}
                  .dump();
  } else {
    std::string all;
    if (w.rank == 0) all.assign(static_cast<std::size_t>(displs.back()) + counts.back(), '\0');
    MPI_Gatherv(packed.data(), static_cast<int>(my_len), MPI_CHAR, all.data(), counts.data(),
                displs.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
    // 3. Rank 0 reassembles in index order and decides.
    if (w.rank == 0) {
      std::optional<Failure> first;
      std::vector<nlohmann::json> per_rank(w.size);
      for (int r = 0; r < w.size; ++r) {
        per_rank[r] =
            nlohmann::json::parse(all.begin() + displs[r], all.begin() + displs[r] + counts[r]);
        const std::optional<Failure> f = failure_from(per_rank[r].at("failure"));
        if (f && (!first || f->index < first->index)) first = f;
      }
      if (first) {
        outcome = nlohmann::json{{"failure", failure_json(first)}}.dump();
      } else {
        results.reserve(n);
        for (int i = 0; i < n; ++i) {
          results.push_back(std::move(per_rank[i % w.size]["results"][i / w.size]));
        }
        outcome = options.results_on_every_rank
                      ? nlohmann::json{{"failure", nullptr}, {"results", results}}.dump()
                      : nlohmann::json{{"failure", nullptr}}.dump();
      }
    }
  }
  broadcast(outcome, w.rank);
  // 4. Everyone acts on the one outcome.
  const nlohmann::json o = nlohmann::json::parse(outcome);
  if (const std::optional<Failure> f = failure_from(o.at("failure"))) raise(*f);
  if (w.rank == 0) return results;
  if (!options.results_on_every_rank) return {};
  return o.at("results").get<std::vector<nlohmann::json>>();
#else
  return {};  // unreachable: w.mpi is false without MPI
#endif
}

namespace {

#ifdef DENTSIM_HAVE_MPI
// The commands that spread their work over the ranks (and `info`, which only prints); every other
// command refuses to start under a launcher with more than one rank (cli/mpi_sweep.h).
bool is_sweep_command(const std::string& name) {
  return name == "zwidth" || name == "bench" || name == "calibrate-seeds" || name == "info";
}
#endif

void setup_launch_guard(CLI::App& app) {
  app.parse_complete_callback([&app] {
    const int size = launcher_size();
    if (size <= 1) return;
    std::string name;
    for (const CLI::App* sub : app.get_subcommands()) name = sub->get_name();
#ifdef DENTSIM_HAVE_MPI
    if (is_sweep_command(name)) return;
    const std::string why = "'dentsim " + name + "' is not a sweep: its " + std::to_string(size) +
                            " copies would do the same work and write the same files; run it "
                            "without mpirun/srun (sweeps: zwidth, bench, calibrate-seeds)";
#else
    const std::string why =
        "this dentsim was built without MPI (DENTSIM_MPI=OFF or no MPI found "
        "at build time): its " +
        std::to_string(size) +
        " copies would each run everything and write the same files; run it "
        "without mpirun/srun, or rebuild with libopenmpi-dev";
#endif
    throw InputError("launched on " + std::to_string(size) + " MPI ranks: " + why);
  });
}
DENTSIM_REGISTER_COMMAND(setup_launch_guard);

}  // namespace
std::string mpi_build_description() {
#ifdef DENTSIM_HAVE_MPI
  // MPI_Get_library_version may be called before MPI_Init.
  char lib[MPI_MAX_LIBRARY_VERSION_STRING];
  int len = 0;
  MPI_Get_library_version(lib, &len);
  std::string first_line(lib, static_cast<std::size_t>(len));
  first_line = first_line.substr(0, first_line.find_first_of(",\n"));
  return "yes (" + first_line + "; launcher " + DENTSIM_MPIEXEC + ")";
#else
  return "no (sweeps run in one process)";
#endif
}

}  // namespace dentsim::cli
