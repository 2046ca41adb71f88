// The Z-width experiment (issue #7; thesis §4.2, Fig. 4.9-4.11; docs/zwidth_protocol.md).
//
// One point = one closed-loop run at 1/T Hz (T = scenario.tick):
//     device (simulated Phantom, or the 1-DoF axis device of zwidth_1dof.h)
//       <-> ClosedLoop (device/closed_loop.h, passivity observer E_v at the device port)
//       <-> ReferencePipeline (reference/tick.h; method explicit / pmi / pmi-pd, with the device
//           model the pipeline believes: built from nominal parameters times the model-error
//           scales, never from the simulator's ground truth)
//       <-> ToothContactProvider over a voxel slab (all enamel) whose top face, normal n = +z
//           (world), lies `approach_gap_m` below the tool-tip sphere at the start.
// The scripted hand (device/scripted_hand.h) is the operator; each operator is one test case:
//   grip    hand impedance (m_h, B_h, K_h) whose reference moves into the wall at grip_speed to the
//           depth where K_h alone would push with push_force, then holds;
//   force   pure force source: -push_force n ramped in over force_ramp_s, no hand mass, stiffness
//           or damping (only the device's own damping dissipates: the strictest operator);
//   tap     the grip hand approaching at each of tap_speeds (one run per speed; the point is
//           stable/passive only if every run is; its Z-width is the smallest of the runs);
//   release grip, then the hand lets go (detached) release_after_s after first contact while the
//           tool is pressed into the wall.
// Every run lasts until hold_s of contact time has passed since the first contact (>= 5 s by
// default), or until a time cap (start + 2 s + hold_s) if contact never starts.
//
// Metrics of a run (signals: device tip penetration p(t) = rho - n^T (x1_true - x_surface)
// [m], from the true tip pose; force fed back f(t) = n^T (J1^T tau_applied)_lin [N], the wrench
// the motors actually applied, with the pipeline's J1 at the sample):
// - Z-width = max f / max p over the run after first contact (thesis §4.2) [N/m];
// - envelope growth rate lambda [1/s]: p is cut into windows of window_s from first contact
//   + settle_s; A_i = max p - min p in window i; lambda = least-squares slope of
//   ln(A_i + Delta_n) against the window centres (Delta_n = encoder quantum at the tip along n);
// - stable  <=> finite, no device fault, held by the wall (hold_s of contact, the proxy never
//   deeper than 2 rho; the device may sink F / K_vc below it), lambda <=
//   ln 2 / (hold_s - settle_s) (the envelope does not double over the hold) and
//   A_last <= amplitude_bound_quanta * Delta_n;
// - passive <=> max_t E_v(t) <= E_tol, E_v the ClosedLoop's passivity observer (energy the
//   virtual side put into the device; E_v <= 0 = passive, the virtual side starts empty) and
//   E_tol = sum_i Delta_i (2 max_k |tau_i,k| + sum_k |tau_i,k - tau_i,k-1|), the largest error
//   encoder quantisation (|q_meas - q_true| < Delta_i) can put into sum_k tau_k^T (q_k+1 - q_k)
//   (summation by parts), plus 1e-9 J round-off;
// - quiet <=> the quiet measures of sim/quiet_measures.h (issue #29) over the contact from
//   first contact + quiet.settle_s to the end of the run meet quiet's bounds: force ripple <= 5 %
//   both of the contact force on the proxy and of the force fed back (what the hand feels),
//   contact on every tick, no contact loss. The oscillation amplitude is that of p, in Delta_n.
//   A point's quiet Z-width counts only points that are stable, passive and quiet.
//
// Bounds beside the measurements (per unit of translational device damping b_d [N s/m] at the
// tip): Colgate-Schenkel passivity of a sampled spring-damper, b_d > K T / 2 + B, i.e.
// K < 2 (b_d - B) / T; thesis §3.1 for PMI virtual coupling,
// b_d >= b_vc (1 + T_k / T_k-1) + k_vc T_k, i.e. k_vc <= (b_d - b_vc (1 + T_k/T_k-1)) / T_k.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sim/quiet_measures.h"
#include "device/scripted_hand.h"
#include "reference/core/params.h"
#include "reference/grip_detector.h"
#include "reference/phantom/phantom_params.h"
#include "validation/zwidth_1dof.h"

namespace dentsim {

enum class ZwidthOperator { kGrip, kForce, kTap, kRelease };
const char* operator_name(ZwidthOperator op);  // "grip", "force", "tap", "release"
// Throws InputError naming the value and the accepted names.
ZwidthOperator parse_operator(const std::string& s);

enum class ZwidthTestbed {
  kAxis,     // the 1-DoF rigid-body device (fast; tests)
  kPhantom,  // the simulated Phantom Premium 1.5/6DoF (MuJoCo; the headline numbers)
};
const char* testbed_name(ZwidthTestbed t);  // "axis", "phantom"
ZwidthTestbed parse_testbed(const std::string& s);

struct ZwidthGains {
  double k_vc = 400.0;      // k_vc,x [N/m] (rotational k_vc,w from rotational_gains)
  double b_vc = 0.0;        // b_vc,x [N s/m]
  double k_tooth = 1500.0;  // K_tooth [N/m] (enamel, scale 1)
};

struct ZwidthScenario {
  ZwidthTestbed testbed = ZwidthTestbed::kAxis;
  double tick = 1e-3;              // nominal T [s]
  double jitter_half_width = 0.0;  // a [s]: T_k uniform on [T - a, T + a]
  std::uint64_t seed = 1;          // jitter seed

  // Device. Axis: `axis` (its period/jitter/seed are taken from above). Phantom: the model file
  // defaults (reference/phantom) with the joint damping replaced by `phantom_damping` if set.
  AxisDeviceParams axis;
  Vec6 phantom_damping = Vec6::Constant(-1.0);  // [N m s/rad]; negative = model file's
  Vec6 phantom_q0 = Vec6::Zero();               // start joint angles [rad]

  // What the pipeline believes about the device (model error): mass/inertia and damping scales.
  double model_mass_scale = 1.0;
  double model_damping_scale = 1.0;
  // Phantom testbed, from device model files (`dentsim zwidth --device MODEL --pipeline-model
  // MODEL`; issue #17: the Z-width with a calibrated model): the simulated device (empty = the
  // default model with phantom_damping) and what the pipeline believes (empty = the device's
  // model with the scales above). Both are used gravity-compensated, as the thesis assumes (2.1);
  // the scales and phantom_damping still apply on top of a file.
  std::optional<PhantomParams> phantom_device_params;
  std::optional<PhantomParams> phantom_pipeline_params;

  // Pipeline.
  // The tick's implementation (fast/registry.h: "reference", "fast"). With "fast" on the Phantom
  // testbed the pipeline evaluates the believed model through fast::PhantomModel; the 1-DoF axis
  // model has one implementation.
  std::string pipeline = "reference";
  ProxyParams proxy;  // m_2, J_2, b_2
  // b_2 = max(proxy.damping_lin, k_vc T / 2): the thesis's proxy-side passivity condition of PMI
  // virtual coupling (§3.1, b_v >= b_vc (T_k/T_k-1 - 1) / 2 + k_vc T_k / 2), applied to every
  // method alike.
  bool proxy_damping_rule = true;
  double k_vc_ang = 0.3;          // k_vc,w [N m/rad]
  double b_vc_ang = 0.002;        // b_vc,w [N m s/rad]
  double observer_gain = 200.0;   // L [1/s], every joint (pmi-pd; docs/zwidth_protocol.md)
  // The observer's input matched to the device's velocity estimate (reference/observer.h,
  // device/device.h matched_observer_input); false = the thesis's discretisation.
  bool observer_input_matched = true;
  // > 0: the pipeline's model carries this fraction of the operator's hand mass and inertia at
  // the tip (reference/grasp_mass_model.h); 0 = the device alone (the hand's inertia then enters
  // the observer's estimate as human force). No effect under `force` (no hand mass) unless
  // grip_detector is set, which then has to find that no hand is on the tool.
  double grasp_mass_scale = 0.0;
  // With grasp_mass_scale > 0: judge tick by tick whether the hand is on the tool
  // (reference/grip_detector.h) and use the hand's mass only while it is; false = always.
  bool grip_detector = false;
  GripDetectorParams grip_detector_params;
  // The method block's remedies of issue #29 (sim/scene.h MethodSpec), for every run of the grid:
  // the encoder Kalman filter's sub-count estimate of the device state (reference/
  // encoder_kalman.h, with the device's encoder quanta) and the loop-lag compensation (reference/
  // lag_compensation.h, with the driver's velocity estimate). Off, as in a scene.
  bool encoder_kalman = false;
  // With encoder_kalman: its prediction's friction (EncoderKalmanParams model_friction and
  // stick_slip; method.encoder_kalman_friction_model "smooth", "none" or "stick_slip").
  bool encoder_kalman_friction = true;
  bool encoder_kalman_stick_slip = false;
  bool lag_compensation = false;
  // true: the pipeline scales tau uniformly into the torque limits (direction kept, reference/
  // tick.h); false: the device clips each joint (the command chain, as OpenHaptics does).
  bool pipeline_saturation = true;
  std::string tool = "explorer";  // tool preset on the locked-inertia floor (pmi-pd)

  // Operator.
  HandImpedance hand;
  double push_force_n = 1.5;
  double force_ramp_s = 0.3;
  double approach_gap_m = 0.5e-3;
  double grip_speed_m_s = 0.02;
  std::vector<double> tap_speeds_m_s = {0.05, 0.15, 0.3};
  double release_after_s = 1.0;
  double hold_s = 5.0;

  // Wall.
  double tip_radius_m = 1.5e-3;   // rho (a contact is at most 2 rho deep: collision.h)
  double voxel_size_m = 0.25e-3;  // h of the slab's voxels
  double b_tooth = 0.0;           // B_tooth [N s/m]

  // Metrics.
  double settle_s = 0.2;
  double window_s = 0.25;
  double amplitude_bound_quanta = 10.0;
  QuietBounds quiet;  // the quiet verdict's bounds and windows (sim/quiet_measures.h)
};

struct ZwidthTrace {
  std::vector<double> t, penetration_m, force_n, energy_j;
  std::vector<int> grip_state;        // TickResult::grip_state
  std::vector<double> grip_statistic;  // TickResult::grip_statistic [N^2/kg]
};

// One closed-loop run.
struct ZwidthRun {
  double approach_speed_m_s = 0.0;  // tap speed (0 for the other operators)
  bool finite = true;
  bool contact = false;
  std::uint32_t faults = 0;
  bool saturated = false;
  double growth_rate_per_s = 0.0;   // lambda
  double growth_limit_per_s = 0.0;  // ln 2 / (hold_s - settle_s)
  double last_amplitude_m = 0.0;    // A_last
  double amplitude_bound_m = 0.0;   // amplitude_bound_quanta * Delta_n
  double energy_max_j = 0.0;        // max_t E_v
  double energy_final_j = 0.0;      // E_v at the end
  double energy_tol_j = 0.0;        // E_tol
  double max_force_n = 0.0;
  double max_penetration_m = 0.0;
  double z_width_n_per_m = 0.0;           // max f / max p
  double static_stiffness_n_per_m = 0.0;  // mean f / mean p over the last second (0 if no contact)
  double contact_time_s = 0.0;
  // The proxy went deeper than 2 rho into the slab at some tick: past the depth the voxel contact
  // can render (reference/tooth/collision.h), it falls through (diagnostic; such a run is
  // unstable).
  bool proxy_tunnelled = false;
  // Grip detector (scenario grip_detector): switches of its state, the fraction of contact ticks
  // its judgement (hand on or off) was right (under `force` no hand is ever on), and (release)
  // the time from letting go to its first "released" (-1: never, or no detector).
  int grip_switches = 0;
  double grip_agreement = -1.0;
  double release_detected_after_s = -1.0;
  // The detector's statistic s [N^2/kg] (0 without one, or without ticks in that phase): its
  // extremes while the hand is on the tool (the whole run before letting go) and its maximum
  // after.
  double grip_statistic_max_on = 0.0, grip_statistic_min_on = 0.0;
  double grip_statistic_max_off = 0.0;
  bool stable = false;
  bool passive = false;
  // The quiet measures of the contact (sim/quiet_measures.h; phase "hold", kind "press";
  // static stiffness there over the same stretch) and their verdict.
  QuietPhase quiet_measures;
  bool quiet = false;
};

struct ZwidthPoint {
  ZwidthGains gains;
  std::vector<ZwidthRun> runs;   // one per tap speed for tap, else one
  bool stable = false;           // every run stable
  bool passive = false;          // every run passive
  bool quiet = false;            // every run quiet
  double z_width_n_per_m = 0.0;  // smallest over the runs
};

// Runs one closed loop. `approach_speed` is used by tap only. `trace` (optional) receives the
// signals of every tick after the start.
ZwidthRun run_zwidth_once(Method method, ZwidthOperator op, const ZwidthGains& gains,
                          const ZwidthScenario& sc, double approach_speed = 0.0,
                          ZwidthTrace* trace = nullptr);
// All runs of one grid point (tap: one per speed).
ZwidthPoint run_zwidth_point(Method method, ZwidthOperator op, const ZwidthGains& gains,
                             const ZwidthScenario& sc);

struct ZwidthGrid {
  std::vector<double> k_vc, b_vc, k_tooth;
  std::size_t size() const { return k_vc.size() * b_vc.size() * k_tooth.size(); }
  // Point i: k_tooth fastest, then k_vc, then b_vc.
  ZwidthGains at(std::size_t i) const;
};

struct ZwidthSweep {
  Method method = Method::kExplicitVc;
  ZwidthOperator op = ZwidthOperator::kForce;
  std::vector<ZwidthPoint> points;  // in grid order
  int best = -1;                    // stable, passive point with the largest Z-width (-1: none)
  double z_width_n_per_m() const { return best < 0 ? 0.0 : points[best].z_width_n_per_m; }
  // The stable, passive and quiet point with the largest Z-width (-1: none), and its Z-width.
  int best_quiet = -1;
  double quiet_z_width_n_per_m() const {
    return best_quiet < 0 ? 0.0 : points[best_quiet].z_width_n_per_m;
  }
};

// Sweeps every (method, operator) over the grid, in parallel over grid points on `threads`
// std::threads (each job builds its own device, pipeline and tooth). `progress(done, total)` is
// called (serialised) after every point. Results in the order methods x operators.
std::vector<ZwidthSweep> run_zwidth_sweep(const std::vector<Method>& methods,
                                          const std::vector<ZwidthOperator>& ops,
                                          const ZwidthGrid& grid, const ZwidthScenario& sc,
                                          int threads,
                                          const std::function<void(int, int)>& progress = {});

// Colgate-Schenkel: largest passive stiffness 2 (b_d - B) / T [N/m] (0 if B >= b_d).
double colgate_schenkel_max_stiffness(double b_device, double b_virtual, double T);
// Thesis §3.1 PMI virtual-coupling bound: largest k_vc with
// b_d >= b_vc (1 + T_k / T_k-1) + k_vc T_k [N/m] (0 if none).
double pmi_coupling_max_stiffness(double b_device, double b_vc, double T_k, double T_km1);

// Translational damping b_d [N s/m] and encoder quantum Delta_n [m] of the testbed's device at
// the tool tip along n = +z at the start pose (Phantom: from J1 and the joint values).
double testbed_tip_damping(const ZwidthScenario& sc);
double testbed_tip_quantum(const ZwidthScenario& sc);

}  // namespace dentsim
