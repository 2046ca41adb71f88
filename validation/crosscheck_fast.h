// `dentsim crosscheck fast`: the fast pipeline against the reference, stage by stage and in
// closed loop (issue #14 "Differential testing", issue #31; docs/tolerance_policy.md).
//
// Stage by stage (open loop, every implementation of the registry, fast/registry.h), on every
// configuration asked for (StageConfig: a built-in scene, a method, the grip detector on or off, a
// contact model; by default the whole matrix: explicit, pmi, pmi-pd, each with and without the
// grip detector, contact models sdf and faces, scenes drill, probe and probe-groove): the
// reference pipeline runs the scene in closed loop, one stage at a time; before each stage its
// data is copied and the other implementation's stage runs on the copy, with that
// implementation's device model and environment (fast::PhantomModel; for faces
// fast::ToothContactProvider over a fast tooth, for sdf the surface proxy on the fast signed
// distance, each drilled in step with the reference's). The stage's outputs are compared:
//   device_terms  M, C^T qd, g, tau_f, J_t, dJ_t/dt, x1, R1, J1, V1, the hand's M_h, C_h^T qd
//   collide       the contact set (same size, members field by field), the deepest penetration
//   assemble      coupling, contact and feed-forward wrenches (f0, G), the PMI system, T1_vc
//   solve         V_hat, the proxy state at k+1, F_contact, F_coupling, T1_pd
//   drill         the number of voxels removed (exact)
//   chain         the implementation's stages from observe on, chained (each fed its own
//                 predecessors' outputs) on a copy of the reference's device terms, with a third
//                 environment queried and drilled once per tick like the reference's: every
//                 output above but device_terms' plus observe's (F1_hat, the observers' p_hat and
//                 f_hat, the grip detector's band powers and state) and command's (tau, T1,
//                 tau_gravity), and every stage's status. It starts after device_terms (which has
//                 its own row) because the observer's estimate is a difference of nearly equal
//                 momenta, f_hat = L (p - p_hat): the device terms' round-off of M becomes a
//                 relative difference of f_hat (and of the grip detector's band powers) orders of
//                 magnitude larger when f_hat is small — the observer's conditioning, not an
//                 error of either implementation, and above the bound.
// Stages an implementation runs with the reference's own code (CheckedImplementation::
// shared_stages; fast: observe and command, fast/tick.cc) have no row of their own: on the same
// input a row would compare a function with itself and could not fail. Their outputs are compared
// in the chain row, where any error planted in them shows (tests/validation/
// crosscheck_fast_test.cc).
// max_rel of a row = the largest over its outputs of |a - b|_inf / |a|_inf, differences of at
// most 1e-15 (SI units) counting as agreement, and every count exact.
//
// Adversarial states (FastCrosscheckOptions::adversarial): on every tick of the stage-by-stage run,
// a copy of the tick's starting state is perturbed in one of the ways below (in turn, tick by
// tick) and every stage but drill runs on it in both implementations (the closed loop goes on
// from the unperturbed state). The perturbed states query a second pair of environments (same
// tooth, never drilled), so the main run's stateful surface proxy never sees them:
//   tick_1e-5, tick_1e-4, tick_1e-2   the tick length T (the loop's own is 1e-3 s)
//   rotation_near_0                   the proxy turned 1e-9 rad off the device's orientation
//   rotation_near_pi                  the proxy turned pi - 1e-9 rad off it (the coupling's
//                                     rotation error at the branch cut of the logarithm)
//   saturation                        torque limits at 1 % of the device's: the command saturates
//   proxy_offset                      the proxy 0.3 mm deeper into the tooth (deeper contact sets,
//                                     and the tip on other voxels' faces, edges and corners)
//   frictionless                      friction off: in contact the solve is the PMI solve of the
//                                     contact system (fast/pmi.h; with friction, the friction
//                                     solve's twin fast/friction.h runs in contact)
//
// Closed loop: each scene runs on both pipelines from the same start; the per-tick difference of
// the force fed back to the device |f(T1_fast) - f(T1_ref)| [N] is recorded with the time where it
// first exceeds 1e-9 N, 1e-6 N and 1e-3 N. Before contact the two runs agree to round-off; in
// contact, drilling (a voxel removed one tick earlier or later) and the saturating device make
// the closed loop chaotic, so differences grow from round-off to the size of the force ripple —
// reported, not hidden (docs/results/fast_crosscheck.md).
#pragma once

#include <array>
#include <atomic>
#include <string>
#include <vector>

#include "reference/core/params.h"
#include "reference/tick.h"

namespace dentsim {

// One configuration of the stage-by-stage check.
struct StageConfig {
  std::string scene = "drill";  // a built-in scene
  Method method = Method::kPmiPd;
  // The grip detector (with the hand's mass, scene key method.grip_detector); off, the pipeline's
  // device model carries the hand's mass all the time (a fixed GraspMassModel).
  bool grip_detector = true;
  std::string contact_model = "faces";  // "sdf" or "faces"
  // Issue #29's loop-lag compensation (scene key method.lag_compensation; "+lag" in the name).
  bool lag_compensation = false;
  // Issue #29's saturation-passive shape control (scene key method.saturation_passive; "+satpass"
  // in the name).
  bool saturation_passive = false;
  // > 0: the hand's feed-forward force in the scene's script keys replaced by this press [N]
  // straight down (-z), on every key that pushes ("+pressN" in the name): a press beyond the
  // device's force, which saturates the command.
  double press_n = 0.0;
  // "drill/faces/pmi-pd+grip": scene/contact model/method, "+grip" with the detector.
  std::string name() const;
};

// Every method (explicit, pmi, pmi-pd) with and without the grip detector, every contact model
// (sdf, faces), on every scene in `scenes`: 12 configurations per scene.
std::vector<StageConfig> stage_config_matrix(const std::vector<std::string>& scenes);
// The 12 (method, grip detector, contact model) combinations once each, the scenes taken in turn
// (each scene gets 12 / scenes.size() of them): every method and contact model, every scene, in a
// twelfth of the matrix's time (CI's form; the matrix is the stress form and the CLI's default).
std::vector<StageConfig> stage_config_cover(const std::vector<std::string>& scenes);

// An implementation checked against the reference.
struct CheckedImplementation {
  const StageTable* table = nullptr;
  // The registered implementation whose device model and environment `table` runs with
  // (build_scene_rig's pipeline name): the table's own name, or "fast" for a test's wrapper.
  std::string environment;
  // Stages the table runs with the reference's own code (TickStage ids): no row of their own,
  // compared in the chain row (header).
  std::vector<int> shared_stages;
};
// Every registered implementation but the reference, with the stages it shares with it.
std::vector<CheckedImplementation> registered_implementations();

struct FastCrosscheckOptions {
  long stage_ticks = 2000;  // ticks of each configuration checked stage by stage
  // Configurations checked stage by stage (default: the whole matrix on the three scenes).
  std::vector<StageConfig> stage_configs = stage_config_matrix({"drill", "probe", "probe-groove"});
  double scene_duration_s = 5.0;  // closed-loop run per scene
  // Built-in scenes; "NAME:faces" runs one with the face contact model.
  std::vector<std::string> scenes = {"drill", "probe", "drill:faces"};
  // Per row. A planted relative error of 1e-9 in any output must fail a row, so the bound sits a
  // factor 10 below it; measured agreement is 1e-13 or better (docs/results/fast_crosscheck.md).
  double max_rel_bound = 1e-10;
  bool adversarial = true;  // also the adversarial states (above)
  // The implementations checked (empty: registered_implementations()).
  std::vector<CheckedImplementation> implementations;
  // Optional stop request (the CLI's SIGINT / SIGTERM flag, cli/interrupt.h), checked before each
  // configuration and scene: once set, crosscheck_fast returns what it has
  // (FastCrosscheckResult::stopped).
  const std::atomic<bool>* stop_request = nullptr;
};

struct StageCrosscheck {
  std::string implementation;  // the implementation checked against "reference"
  std::string config;          // StageConfig::name()
  std::string stage;           // a stage of the tick (not a shared one), or "chain"
  double max_rel = 0.0;
  long samples = 0;           // stage evaluations compared
  long contact_samples = 0;   // ... of which with a nonempty contact set
  long count_mismatches = 0;  // contact-set sizes, removed-voxel counts, statuses that differ
};

// One adversarial perturbation, over its stages (every stage but drill and the shared ones).
struct AdversarialCrosscheck {
  std::string implementation;
  std::string config;
  std::string perturbation;  // "tick_1e-5", ...
  std::string stage;
  double max_rel = 0.0;
  long samples = 0, contact_samples = 0;
  long count_mismatches = 0;   // contact-set sizes, statuses
  long saturated_samples = 0;  // ticks whose command saturated
};

struct SceneCrosscheck {
  std::string scene;
  std::string implementation;
  long ticks = 0;
  long contact_ticks = 0;
  double max_force_diff_n = 0.0;
  double max_force_diff_before_contact_n = 0.0;  // up to the first contact tick
  double first_contact_s = -1.0;
  double diverged_1e9_s = -1.0, diverged_1e6_s = -1.0, diverged_1e3_s = -1.0;  // -1: never
  double max_force_n = 0.0;             // the reference's largest force (scale of the difference)
  std::vector<double> t, force_diff_n;  // per tick (for the plot)
};

// A stage without a row of its own, and why.
struct SharedStage {
  std::string implementation;
  std::string stage;
  std::string reason;
};

struct FastCrosscheckResult {
  std::vector<StageCrosscheck> stages;
  std::vector<SceneCrosscheck> scenes;
  std::vector<AdversarialCrosscheck> adversarial;
  std::vector<SharedStage> shared;
  // Contact members of the stage-by-stage run per material id (reference/tooth/materials.h): which
  // materials the comparison saw (enamel, dentin, caries, pulp).
  std::array<long, 8> contact_members_per_material{};
  bool ok = true;  // every row within max_rel_bound, no count mismatch, closed loop bounded
  std::vector<std::string> failures;
  // The stop request ended it early: the configurations and scenes before `stopped_at` ran.
  bool stopped = false;
  std::string stopped_at;
};

FastCrosscheckResult crosscheck_fast(const FastCrosscheckOptions& options);

}  // namespace dentsim
