// The friction solve's input on a built-in scene's contact ticks, recorded from the fast
// pipeline's closed loop: what tests/fast/friction_test.cc compares the friction solves of the
// registry (fast/registry.h, Implementation::friction) on, and what bench/tick_bench.cc's
// BM_Friction times them on.
#pragma once

#include <string>
#include <vector>

#include "reference/friction.h"

namespace dentsim {

// One call of the solve stage's friction solve: its arguments.
struct FrictionState {
  PmiSystem sys;
  std::vector<Contact> contacts;
  Pose proxy;
  AffineWrench normal;
  FrictionParams fp;
};

// Runs the built-in `scene` (its contact model, the fast pipeline, the simulated Phantom in closed
// loop) for `ticks` ticks and returns the solve stage's input on every tick whose contact set is
// not empty (the ticks on which the stage calls the friction solve when friction is enabled).
// The loop is the pipeline's own stages tick by tick (as validation/crosscheck_fast.h drives
// them), stopped after assemble to copy the input. Throws what the scene and rig throw, and
// std::runtime_error when a tick fails.
std::vector<FrictionState> record_friction_states(const std::string& scene, long ticks);

}  // namespace dentsim
