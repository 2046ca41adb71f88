// `dentsim crosscheck fast`: the fast pipeline against the reference, stage by stage and in
// closed loop (issue #14 "Differential testing"; docs/tolerance_policy.md).
//
// Stage by stage (open loop, every implementation of the registry, fast/registry.h): the
// reference pipeline runs the drill scene (face contact model, grip detector on) in closed loop,
// one stage at a time; before each stage its data is copied and the other implementation's stage
// runs on the copy, with that implementation's device model and environment (fast::PhantomModel,
// fast::ToothContactProvider over a fast tooth kept in the same drilled state). The stage's outputs
// are compared:
//   device_terms  M, C^T qd, g, tau_f, J_t, dJ_t/dt, x1, R1, J1, V1, the hand's M_h, C_h^T qd
//   observe       F1_hat, the observers' p_hat and f_hat, the grip detector's band powers
//   collide       the contact set (same size, members field by field), the deepest penetration
//   assemble      coupling, contact and feed-forward wrenches (f0, G), the PMI system, T1_vc
//   solve         V_hat, the proxy state at k+1, F_contact, F_coupling, T1_pd
//   command       tau, T1, tau_gravity
//   drill         the number of voxels removed (exact)
// max_rel of a stage = the largest over its outputs of |a - b|_inf / |a|_inf, differences of at
// most 1e-15 (SI units) counting as agreement, and every count exact.
//
// Adversarial states (FastCrosscheckOptions::adversarial): on every tick of the stage-by-stage run,
// a copy of the tick's starting state is perturbed in one of the ways below (in turn, tick by
// tick) and every stage but drill runs on it in both implementations (the closed loop goes on
// from the unperturbed state; drilling is compared there):
//   tick_1e-5, tick_1e-4, tick_1e-2   the tick length T (the loop's own is 1e-3 s)
//   rotation_near_0                   the proxy turned 1e-9 rad off the device's orientation
//   rotation_near_pi                  the proxy turned pi - 1e-9 rad off it (the coupling's
//                                     rotation error at the branch cut of the logarithm)
//   saturation                        torque limits at 1 % of the device's: the command saturates
//   proxy_offset                      the proxy 0.3 mm deeper into the tooth (deeper contact sets,
//                                     and the tip on other voxels' faces, edges and corners)
//
// Closed loop: each scene runs on both pipelines from the same start; the per-tick difference of
// the force fed back to the device |f(T1_fast) - f(T1_ref)| [N] is recorded with the time where it
// first exceeds 1e-9 N, 1e-6 N and 1e-3 N. Before contact the two runs agree to round-off; in
// contact, drilling (a voxel removed one tick earlier or later) and the saturating device make
// the closed loop chaotic, so differences grow from round-off to the size of the force ripple —
// reported, not hidden (docs/results/fast_crosscheck.md).
#pragma once

#include <array>
#include <string>
#include <vector>

namespace dentsim {

struct FastCrosscheckOptions {
  long stage_ticks = 2000;        // ticks of the drill scene checked stage by stage
  double scene_duration_s = 5.0;  // closed-loop run per scene
  // Built-in scenes; "NAME:faces" runs one with the face contact model (whose tooth has a fast
  // twin; the scenes' default surface-proxy contact runs the reference provider in both).
  std::vector<std::string> scenes = {"drill", "probe", "drill:faces"};
  double max_rel_bound = 1e-9;  // per stage (the policy's aim is 1e-12; see the doc)
  bool adversarial = true;      // also the adversarial states (above)
};

struct StageCrosscheck {
  std::string implementation;  // the implementation checked against "reference"
  std::string stage;
  double max_rel = 0.0;
  long samples = 0;           // stage evaluations compared
  long contact_samples = 0;   // ... of which with a nonempty contact set
  long count_mismatches = 0;  // contact-set sizes or removed-voxel counts that differ
};

// One adversarial perturbation, over its stages (every stage but drill).
struct AdversarialCrosscheck {
  std::string implementation;
  std::string perturbation;  // "tick_1e-5", ...
  std::string stage;
  double max_rel = 0.0;
  long samples = 0, contact_samples = 0;
  long count_mismatches = 0;   // contact-set sizes, statuses
  long saturated_samples = 0;  // ticks whose command saturated (command stage)
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

struct FastCrosscheckResult {
  std::vector<StageCrosscheck> stages;
  std::vector<SceneCrosscheck> scenes;
  std::vector<AdversarialCrosscheck> adversarial;
  // Contact members of the stage-by-stage run per material id (reference/tooth/materials.h): which
  // materials the comparison saw (enamel, dentin, caries, pulp).
  std::array<long, 8> contact_members_per_material{};
  bool ok = true;  // every stage within max_rel_bound, no count mismatch, closed loop bounded
  std::vector<std::string> failures;
};

FastCrosscheckResult crosscheck_fast(const FastCrosscheckOptions& options);

}  // namespace dentsim
