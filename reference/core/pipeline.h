// The servo tick as Model/Data stages (docs/design.md "The tick as Model/Data stages"; MuJoCo's
// mjModel/mjData, Pinocchio's model/data). Shared by reference/ and fast/: both implement the
// same stage list over the same PipelineModel and PipelineData, and one registry of stage
// tables (StageTable) drives the tick, the differential tests, the benchmarks and the
// allocation-counting test.
//
//   PipelineModel  everything constant for a run: the device model, gains, proxy inertia, tool
//                  dynamics and its factorisation, observer and grip-detector parameters, the
//                  torque limits. Built and validated once (make_pipeline_model in
//                  reference/tick.h), with the messages users get for bad configurations.
//   PipelineData   everything that changes, allocated once: the sample, the device terms, the
//                  observer and grip states, the proxy, the fixed-capacity contact buffer, the
//                  assembled force elements, the solve, the command and the result.
//
// The stages, in order (stage(const PipelineModel&, PipelineData&) -> TickStatus):
//   device_terms  one pass of the device model at (q, qd): x1, R1, J_t, M, C^T qd, g, tau_f
//                 (+ dJ_t/dt and the hand's inertia when a grasp mass is modelled); J1 = J_t^-1
//                 (the one factorisation a tick needs); V1 = J_t qd                         (2.2)
//   observe       the momentum observer (3.7)-(3.8), or the grip detector's two observers,
//                 -> F1_hat = J1^T f1_hat
//   collide       the environment's contact set at the proxy pose (ContactProvider)
//   assemble      the force elements affine in V_hat: coupling (4.5), contact (2.16)/(2.19),
//                 decomposition feed-forward (4.7); the device-side coupling (4.3)-(4.4)
//   solve         PMI (4.9) with friction (2.21)-(2.22), or explicit Euler; the proxy advances
//   command       T1 = T1_vc + T1_pd -> tau = J_t^T T1 (+ g(q)), saturated; finite check
//   drill         the tool's cut of the environment over the tick (ContactProvider::drill)
//
// A tick never allocates and never throws: it returns a TickStatus, and on anything but kOk the
// result's torque is zero; the loop owner (device/closed_loop.h) latches the status as a named
// fault and keeps commanding zero torque.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "reference/core/affine_wrench.h"
#include "reference/core/contact_provider.h"
#include "reference/core/device_model.h"
#include "reference/core/params.h"

namespace dentsim {

// ---- status --------------------------------------------------------------------------------

enum class TickStatus : std::uint8_t {
  kOk = 0,
  kBadTickLength,       // T not finite or <= 0
  kBadSample,           // q, qd or t not finite, or not 6 joints
  kDeviceModelFailure,  // device terms not finite, J_t singular, or the locked inertia not SPD
  kContactBufferFull,   // the contact set did not fit the buffer (kContactCapacity)
  kBadContact,          // a contact from the environment is malformed (contact.h's rules)
  kSolverFailure,       // the PMI / friction system is singular or not finite
  kNonFiniteOutput,     // the torque or the proxy state is not finite
  kDrillWorkTableFull,  // the drill's per-voxel work table is full (ContactProvider::drill_store_full)
  kFieldEditShortfall,  // the field model's edit fell short: no spare brick or queue slot
                        // (ContactProvider::field_edit_shortfall)
};
// The fault name: "ok", "tick_bad_length", "tick_bad_sample", "tick_device_model_failure",
// "tick_contact_buffer_full", "tick_bad_contact", "tick_solver_failure", "tick_non_finite_output",
// "tick_drill_work_table_full", "tick_field_edit_shortfall".
const char* tick_status_name(TickStatus s);

// ---- stages --------------------------------------------------------------------------------

// X-macro of the stage list, in tick order: X(enumerator, name).
#define DENTSIM_TICK_STAGES(X)         \
  X(kStageDeviceTerms, "device_terms") \
  X(kStageObserve, "observe")          \
  X(kStageCollide, "collide")          \
  X(kStageAssemble, "assemble")        \
  X(kStageSolve, "solve")              \
  X(kStageCommand, "command")          \
  X(kStageDrill, "drill")

enum TickStage : int {
#define DENTSIM_STAGE_ENUM(id, name) id,
  DENTSIM_TICK_STAGES(DENTSIM_STAGE_ENUM)
#undef DENTSIM_STAGE_ENUM
      kStageCount
};
const char* tick_stage_name(int stage);  // "device_terms", ..., "drill"; "?" out of range

// ---- model ---------------------------------------------------------------------------------

// The hand's nominal mass on the tool tip (reference/grasp_mass_model.h): in maximal coordinates
// the constant inertia Mt = diag(m I, J I); in joint space M_h = J_t^T Mt J_t and
// C_h^T qd = dJ_t/dt^T Mt V1.
struct GraspMass {
  double mass = 0.0;       // m [kg]
  double inertia = 0.0;    // J [kg m^2]
  Vec6 Mt = Vec6::Zero();  // diagonal of Mt
};

struct PipelineModel {
  const SixDofDeviceModel* device = nullptr;  // must outlive the model
  Method method = Method::kPmiVc;
  Scheme scheme = Scheme::kMidpoint;  // kExplicit for kExplicitVc
  ProxyParams proxy;
  CouplingGains coupling;
  FrictionParams friction;
  ToolDynamics tool;
  // M_d = L L^T, factorised once (kPmiPd). Built on the identity so a model that never
  // factorises (every other method) still copies a defined info() (UBSan: Eigen leaves it unset).
  Eigen::LLT<Mat6> tool_Md_llt{Mat6::Identity()};
  // M_d and D_d diagonal (every off-diagonal entry exactly zero), decided once with the tool: the
  // fast twin's feed-forward then takes its block-structured path (fast/decomposition.h).
  bool tool_diagonal = false;
  bool observe = false;               // an observer runs (gain set)
  Vec6 observer_gain = Vec6::Zero();  // L [1/s]
  ObserverInput observer_input;
  bool grasp = false;  // the grip detector runs (a hand mass is modelled)
  GraspMass grasp_mass;
  GripDetectorParams grip;
  Vec6 grip_norm = Vec6::Zero();  // its norm's diagonal: 1/m on the force, 0 on torque
  bool saturate = false;
  Vec6 torque_limit = Vec6::Zero();  // [N m]
  bool compensate_gravity = true;
  // The encoder Kalman filter (reference/encoder_kalman.h; issue #29): device_terms replaces the
  // sample's quantised (q, qd) by the filter's sub-count estimate, which every later stage uses.
  bool encoder_kalman = false;
  Vec6 encoder_quantum = Vec6::Zero();  // per joint [rad]; 0 = that joint is not quantised
  EncoderKalmanParams encoder_kalman_params;
  // With encoder_kalman_params.stick_slip: the device model's joint friction coefficients
  // (SixDofDeviceModel::joint_friction_coefficients), viscous b and Coulomb f_c per joint.
  Vec6 encoder_friction_b = Vec6::Zero();
  Vec6 encoder_friction_fc = Vec6::Zero();
  // Loop-lag compensation (reference/lag_compensation.h; issue #29): device_terms sets V1 =
  // J_t (qd + lag a) with the lag of `velocity_estimate` (none with the encoder Kalman filter)
  // plus the zero-order hold's half tick, a the device model's acceleration.
  bool lag_compensation = false;
  ObserverInput velocity_estimate;
  // Shape control passive under actuator saturation (reference/saturation_passive.h; issue #29):
  // set only together with `saturate`.
  bool saturation_passive = false;
  // Skip what the scene does not need (fast/ only; fast/README.md "Skips"): the observer without
  // a gain, the grip detector without a hand mass, the decomposition unless the method uses it,
  // friction when off, contact work on an empty set, drilling unless the tool drills, the tooth's
  // free-space early out. false runs every one of them and discards what the method does not
  // use: the same torques (tests/fast/skip_test.cc), for checks and for bench/skip_bench.cc.
  bool skip_unneeded = true;
  // Time each stage into TickResult::stage_ns (one steady_clock read per stage and one before
  // them). false: no clock is read and stage_ns stays zero; nothing else changes (the same
  // torques, bitwise). For callers that never read the times (the Z-width sweeps).
  bool time_stages = true;
};

// ---- data ----------------------------------------------------------------------------------

// Momentum observer state (reference/observer.h), for any vector type (VecX: n-DoF, Vec6: tick).
template <class V>
struct MomentumObserverState {
  V p_hat, f_hat, beta_prev, tau_prev, u_f;
  bool ready = false;
};

// The encoder Kalman filter's estimate (reference/encoder_kalman.h).
struct EncoderKalmanState {
  Vec6 q = Vec6::Zero();   // estimated joint angles
  Vec6 qd = Vec6::Zero();  // estimated joint velocities
  bool ready = false;
};

// The grip detector's filters and decision (reference/grip_detector.h).
struct GripFilterState {
  Vec6 h0 = Vec6::Zero(), h1 = Vec6::Zero();    // estimates of H0 (no hand) and H1 (gripped)
  Vec6 b0 = Vec6::Zero(), b1 = Vec6::Zero();    // h_i low-passed at lowpass_hz
  Vec6 lp0 = Vec6::Zero(), lp1 = Vec6::Zero();  // b_i low-passed at highpass_hz
  double p0 = 0.0, p1 = 0.0;                    // band powers
  double g_release = 0.0, g_grip = 0.0;         // CUSUM sums
  bool gripped = true;
};

// The grip filter's gains for a tick of length T (reference/grip_detector.h grip_filter_gains):
// 1 - exp(-2 pi f T) at its low-pass, high-pass and band-power cut-offs.
struct GripFilterGains {
  double a_lp = 0.0, a_hp = 0.0, a_p = 0.0;
};

// The gains of the last kSize distinct tick lengths (fast/tick.cc's observe). They are a function
// of T alone (the model's filter constants fixed), and the measured tick length t - t_prev takes
// a few values that differ by round-off, so the three exp run only for a T not kept here: the same
// doubles as evaluating them each tick. Emptied by the fast twin's reset.
struct GripGainMemo {
  static constexpr int kSize = 4;
  double T[kSize] = {std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::quiet_NaN()};  // NaN: empty (never == T)
  GripFilterGains g[kSize];
  int next = 0;  // the slot the next new T replaces (round robin)
};

// The tick's fixed-capacity contact buffer: a vector reserved to kContactCapacity that keeps that
// capacity when copied (a copy of PipelineData is a working tick state too, e.g. in the
// differential tests). Providers fill it without growing it (contact_provider.h).
class ContactBuffer : public std::vector<Contact> {
 public:
  ContactBuffer() { reserve(kContactCapacity); }
  ContactBuffer(const ContactBuffer& o) : std::vector<Contact>() {
    reserve(kContactCapacity);
    assign(o.begin(), o.end());
  }
  ContactBuffer& operator=(const ContactBuffer& o) {
    if (this != &o) assign(o.begin(), o.end());
    return *this;
  }
  ContactBuffer(ContactBuffer&&) = default;
  ContactBuffer& operator=(ContactBuffer&&) = default;
};

// Everything one tick computed (for logging, tests and the fast path's differential tests).
struct TickResult {
  TickStatus status = TickStatus::kOk;
  Pose device;                       // x1, R1
  Vec6 V1 = Vec6::Zero();            // device twist (lag-compensated when the model says so)
  Vec6 F1_hat = Vec6::Zero();        // human wrench estimate (maximal), zero without observer
  Vec6 T1_vc = Vec6::Zero();         // coupling wrench on the device
  Vec6 T1_pd = Vec6::Zero();         // decomposition feed-forward on the device
  Vec6 T1 = Vec6::Zero();            // total device wrench before saturation
  VecX tau = VecX::Zero(6);          // joint torques sent to the device (saturated)
  VecX tau_gravity = VecX::Zero(6);  // the gravity-compensation part of tau (zero when off)
  bool saturated = false;
  // Saturation-passive shape control (reference/saturation_passive.h): the feed-forward's scale
  // sigma this tick used (1 = untouched) and the cap on the coupling's linear spring force [N]
  // (0 = no cap this tick).
  double shape_sigma = 1.0;
  double coupling_force_cap = 0.0;
  Vec6 V_hat = Vec6::Zero();       // proxy velocity the forces were evaluated at
  Vec6 F_contact = Vec6::Zero();   // contact + friction wrench on the proxy at V_hat
  Vec6 F_coupling = Vec6::Zero();  // coupling wrench on the proxy at V_hat
  ContactBuffer contacts;          // the contact set of this tick (capacity kContactCapacity)
  double max_depth = 0.0;          // deepest penetration in the set [m]
  bool friction_sliding = false;
  int grip_state = -1;              // grip detector: 1 gripped, 0 released, -1 no detector
  double grip_statistic = 0.0;      // its statistic s [N^2/kg]
  int removed_voxels = 0;           // voxels the drill stage removed this tick
  long stage_ns[kStageCount] = {};  // wall-clock time of each stage [ns] (steady_clock)
};

struct PipelineData {
  // Input of this tick.
  Vec6 q = Vec6::Zero(), qd = Vec6::Zero();
  double t = 0.0;        // sample time [s]
  double T = 1e-3;       // length of the tick about to run [s]
  double T_last = 1e-3;  // length of the tick that just ended (observer input) [s]
  ContactProvider* env = nullptr;

  // device_terms
  DeviceTerms dev;
  Eigen::PartialPivLU<Mat6> J_t_lu;
  Mat6 J1 = Mat6::Identity();     // J_t^-1: qd = J1 V1 (2.2)
  Mat6 M_hand = Mat6::Zero();     // J_t^T Mt J_t (grasp)
  Vec6 CTqd_hand = Vec6::Zero();  // dJ_t/dt^T Mt V1 (grasp)

  // device_terms: the encoder Kalman filter's state (PipelineModel::encoder_kalman)
  EncoderKalmanState enc;

  // observe
  MomentumObserverState<Vec6> obs0, obs1;  // obs0: the device (H0), obs1: device + hand (H1)
  GripFilterState grip;
  GripGainMemo grip_gains;  // the fast twin's (the reference evaluates the gains each tick)
  Vec6 tau_prev = Vec6::Zero();  // torque applied over the tick that just ended
  double t_prev = 0.0;
  bool have_prev = false;

  // assemble / command: the saturation-passive shape control's state (PipelineModel::
  // saturation_passive): the feed-forward scale sigma in [0, 1], lowered by each saturated
  // command, and whether the coupling's force cap bound in this tick's assemble.
  double shape_sigma = 1.0;
  bool shape_engaged = false;  // a command saturated and the device is not yet back inside
  bool coupling_capped = false;

  // assemble / solve
  ProxyState proxy;
  AffineWrench coupling, contact, pd_T1, pd_T2;
  // The fast twin keeps the feed-forward T1 factored (fast/decomposition.h
  // pd_feedforward_diagonal_factored): T1(V) = pd_M1 pd_W(V) - r.F1_hat, and pd_T1 is not formed.
  // The tick reads T1 at V_hat only, through pd_T1_at below. The reference forms pd_T1.
  bool pd_T1_factored = false;
  Mat6 pd_M1 = Mat6::Zero();
  AffineWrench pd_W;
  PmiSystem sys;

  TickResult r;
};

// The feed-forward T1 at V: pd_T1's, or from its factors (PipelineData::pd_T1_factored).
inline Vec6 pd_T1_at(const PipelineData& d, const Vec6& V) {
  if (!d.pd_T1_factored) return d.pd_T1.at(V);
  const Vec6 w = d.pd_W.at(V);
  Vec6 t;
  t.noalias() = d.pd_M1 * w;
  return t - d.r.F1_hat;
}

// pd_T1 itself, formed from its factors when kept factored (the differential tests' view).
inline AffineWrench pd_T1_formed(const PipelineData& d) {
  if (!d.pd_T1_factored) return d.pd_T1;
  AffineWrench T1;
  T1.f0.noalias() = d.pd_M1 * d.pd_W.f0;
  T1.f0 -= d.r.F1_hat;
  T1.G.noalias() = d.pd_M1 * d.pd_W.G;
  return T1;
}

// ---- registry ------------------------------------------------------------------------------

using StageFn = TickStatus (*)(const PipelineModel&, PipelineData&);

// One implementation of the tick: a function per stage, in TickStage order, plus the reset.
struct StageTable {
  const char* implementation;  // "reference", "fast"
  std::array<StageFn, kStageCount> stage;
  // Places the proxy on the device pose at rest and resets the observers on the sample in `d`
  // (d.q, d.qd, d.t set); runs the device_terms stage itself.
  TickStatus (*reset)(const PipelineModel&, PipelineData&);
};

// Copies the sample into `d` and runs `table`'s reset. kBadSample for a malformed sample.
TickStatus pipeline_reset(const StageTable& table, const PipelineModel& m, PipelineData& d,
                          const DeviceSample& s);
// One tick: checks T and the sample, runs every stage in order (timing each into
// d.r.stage_ns when m.time_stages, else leaving it zero), stops at the first failing stage. On failure d.r.tau and d.r.tau_gravity are
// zero and d.r.status names the failure. Never allocates, never throws.
TickStatus pipeline_tick(const StageTable& table, const PipelineModel& m, PipelineData& d,
                         const DeviceSample& s, double T, ContactProvider& env);

}  // namespace dentsim
