// `dentsim info`: what this build is and which libraries it links.
#include <cstdio>
#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include "cli/registry.h"

namespace dentsim::cli {
namespace {

void setup_info(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("info", "Print the build configuration and library versions");
  sub->callback([] {
    std::printf("dentsim 0.1.0\n");
    std::printf("  MuJoCo %d (header %d)\n", mj_version(), mjVERSION_HEADER);
    std::printf("  Eigen %d.%d.%d\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
  });
}
DENTSIM_REGISTER_COMMAND(setup_info);

}  // namespace
}  // namespace dentsim::cli
