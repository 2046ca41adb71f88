// The scene variants that reach each of the fast pipeline's skips (PipelineModel::skip_unneeded;
// issue #14 "Skip what a scene does not need, each skip measured in a benchmark and checked equal
// to not skipping"). One list drives both: tests/fast/skip_test.cc runs every variant with skips on
// and off and checks the torques equal tick by tick; bench/skip_bench.cc times the same runs.
//
// The skips, and where a variant reaches them:
//   observer       a method without an observer gain (pmi, explicit): skipped -> the observers
//                  run at gain 0 with skips off (their estimate stays zero)
//   grip           no hand mass: the grip detector's second hypothesis equals the first
//   decomposition  pmi and explicit: the decomposition and feed-forward (4.7), never applied
//   friction       friction off: the friction solver at mu = 0 (fast/friction.h: the PMI
//                  solve's own factor and solve, so bitwise the skip's fast::pmi_try_solve)
//   drill          a tool that does not drill: the environment asked to cut anyway
//   empty set      every variant's free-space ticks: the contact wrench of an empty set
//   early out      the face model's free-space box test (fast/tooth/brick_tooth.h)
// The rotation-free tool is not among them: every tool in dentsim has its tip offset from the
// handle frame (tool presets), so the contact torque never vanishes and the proxy's rotational
// dynamics are always needed.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {

struct SkipVariant {
  std::string name;   // short id (benchmark names): "pmi-no-observer", ...
  std::string skips;  // what it exercises, for messages and tables
  std::string scene;  // built-in scene
  std::function<void(Scene&)> edit_scene;
  std::function<void(PipelineConfig&)> edit_config;  // SceneRigOptions::configure_pipeline
};

const std::vector<SkipVariant>& skip_variants();

// The variant's rig on the fast pipeline with skips on or off.
std::unique_ptr<SceneRig> build_skip_variant_rig(const SkipVariant& v, bool skip_unneeded);

}  // namespace dentsim
