// `dentsim info`: what this build is and which libraries it links.
#include <cstdio>
#include <string>
#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include "cli/registry.h"

#ifdef DENTSIM_HAVE_MPI
// The C API only: Open MPI's and MPICH's mpi.h otherwise pull in the deprecated C++ bindings,
// which need libmpi_cxx.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace dentsim::cli {
namespace {

void setup_info(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("info", "Print the build configuration and library versions");
  sub->callback([] {
    std::printf("dentsim 0.1.0\n");
    std::printf("  MuJoCo %d (header %d)\n", mj_version(), mjVERSION_HEADER);
    std::printf("  Eigen %d.%d.%d\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
    // Whether `mpirun -n N dentsim zwidth|bench|calibrate-seeds` spreads the sweep over the ranks
    // (docs/scaling.md); tests/cli/mpi_sweep_test.cc reads this line. MPI_Get_library_version
    // may be called before MPI_Init.
#ifdef DENTSIM_HAVE_MPI
    char lib[MPI_MAX_LIBRARY_VERSION_STRING];
    int len = 0;
    MPI_Get_library_version(lib, &len);
    std::string first_line(lib, static_cast<std::size_t>(len));
    first_line = first_line.substr(0, first_line.find_first_of(",\n"));
    std::printf("  MPI: yes (%s; launcher %s)\n", first_line.c_str(), DENTSIM_MPIEXEC);
#else
    std::printf("  MPI: no (sweeps run in one process)\n");
#endif
  });
}
DENTSIM_REGISTER_COMMAND(setup_info);

}  // namespace
}  // namespace dentsim::cli
