// `dentsim info`: what this build is and which libraries it links.
#include <cstdio>
#include <string>
#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include "cli/mpi_sweep.h"
#include "cli/registry.h"

namespace dentsim::cli {
namespace {

void setup_info(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("info", "Print the build configuration and library versions");
  sub->callback([] {
    std::printf("dentsim 0.1.0\n");
    std::printf("  MuJoCo %d (header %d)\n", mj_version(), mjVERSION_HEADER);
    std::printf("  Eigen %d.%d.%d\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
    // Whether `mpirun -n N dentsim zwidth|bench|calibrate-seeds` spreads the sweep over the ranks
    // (docs/scaling.md); tests/cli/mpi_sweep_test.cc reads this line.
    std::printf("  MPI: %s\n", mpi_build_description().c_str());
  });
}
DENTSIM_REGISTER_COMMAND(setup_info);

}  // namespace
}  // namespace dentsim::cli
