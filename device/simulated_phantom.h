// The simulated haptic device: a MuJoCo plant run as sampled-data hardware (docs/design.md
// "The simulated device", issue #3). Each effect is configurable and tested (tests/device/):
//
// - Sub-stepping: tick k of length T_k [s] is integrated in N_k = ceil(T_k / max_substep) MuJoCo
//   steps of h_k = T_k / N_k (RK4 by default).
// - Zero-order hold: the applied joint torque tau_k is set once per tick and held over all of
//   its substeps (qfrc_applied on the device dofs; Q = P^T tau, see mujoco_plant.h).
// - Encoder quantisation: q_i = Delta_i floor(q_true,i / Delta_i), with
//   Delta_i = 2 pi / (quadrature * counts_per_rev * ratio_i)   [rad]
//   (Phantom: 1024 CPR, x4 quadrature, capstan ratios 13.3, 11.2, 11.2 -> ~1.2e-4..1.4e-4 rad;
//   the gimbal ratios are not published, assumed 1).
// - Velocity: qd from the quantised q by the driver's estimator (velocity_estimator.h) over the
//   device clock's tick length.
// - Saturation: the applied torque is clipped to +-tau_max (OpenHaptics' joint-torque clamp,
//   (400, 350, 200, 188, 188, 48) mN m); a command beyond tau_fault is a fault (device.h).
//   Optionally (config.torque_limit kThermal) tau_max is the motors' peak and a thermal model of
//   each motor lowers the limit of a tick when the winding would overheat over it
//   (device/motor_thermal.h): derated towards the continuous rating, or the fault
//   motor_temperature with zero torque.
// - Joint damping b [N m s/rad] and Coulomb frictionloss f_c [N m] on the device dofs (MuJoCo's
//   own dof_damping / dof_frictionloss, so the integrator and the constraint solver treat them).
//   They are not published for the Phantom: the defaults below are assumptions to be replaced by
//   calibration (calibration/).
// - Tick jitter: T_k constant, uniform on [T - a, T + a], normal N(T, sigma^2), or a replayed
//   trace of measured tick lengths (cycled); seeded (std::mt19937_64). A drawn T_k <= 0 is a
//   clock fault: the physics does not run backwards, the sample's time does not increase and the
//   device latches kFaultNonMonotonicTime.
// - The scripted hand (scripted_hand.h): its mass and inertia are added to the tip body (the
//   human carries its weight: -m_h g is applied at the tip with it), its
//   wrench is recomputed at every substep from the tip state and applied to the tip body through
//   xfrc_applied (force at the tip point, world frame), so the device physics sees it. The hand's
//   true wrench and its joint torques G^T J^T F (time-averaged over the tick) are exposed as
//   ground truth.
//
// Frames: tip pose (x, R) in world {O}; twist V = [v (world); w (body)]; wrench F = [f (world);
// tau (body)].
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "device/device.h"
#include "device/motor_thermal.h"
#include "device/scripted_hand.h"
#include "device/velocity_estimator.h"
#include "plant/mujoco_plant.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

enum class TickJitterKind { kNone, kUniform, kNormal, kTrace };

struct TickJitter {
  TickJitterKind kind = TickJitterKind::kNone;
  double period = 1e-3;       // nominal T [s] (mean of uniform/normal)
  double half_width = 0.0;    // a [s] of the uniform distribution
  double sigma = 0.0;         // sigma [s] of the normal distribution
  std::vector<double> trace;  // tick lengths [s] replayed in order, cycled
  std::uint64_t seed = 1;
};

struct SimulatedDeviceConfig {
  double max_substep = 2.5e-4;  // [s] largest MuJoCo step inside a tick
  bool rk4 = true;              // RK4 integrator (false: the MJCF's integrator)
  bool gravity = true;          // false: gravity off in the plant
  // Encoders.
  bool quantize = true;
  int counts_per_rev = 1024;
  int quadrature = 4;
  VecX drive_ratio;      // per joint (empty: Phantom (13.3, 11.2, 11.2, 1, 1, 1) or 1)
  VecX encoder_quantum;  // per joint [rad or m] (non-empty: overrides the formula)
  // Velocity from quantised angles.
  VelocityEstimatorParams velocity;
  // Motor torque.
  bool saturate = true;
  VecX tau_max;                 // [N m] (empty: Phantom defaults for 6 joints, else 1)
  VecX tau_fault;               // [N m] (empty: 4 tau_max)
  double max_joint_step = 0.1;  // [rad] encoder-jump fault threshold per tick
  // Motor torque limit model (device/motor_thermal.h): kClamp (default) clips to tau_max only;
  // kThermal (6 joints) adds each motor's thermal limit below tau_max (set tau_max to its peak).
  MotorThermalParams torque_limit;
  // Joint damping and friction of the device dofs.
  bool damping_on = true;
  bool friction_on = true;
  VecX damping;       // [N m s/rad] (empty: the MJCF's dof_damping)
  VecX frictionloss;  // [N m] (empty: the MJCF's dof_frictionloss)
  // How the device dofs' Coulomb friction f_c acts. kFrictionloss (default): MuJoCo's
  // dof_frictionloss, a soft constraint solved with the dynamics (it holds a joint at rest with
  // any torque up to f_c). kTanh: the device model's law -f_c tanh(qd / coulomb_velocity_i) as an
  // applied torque, evaluated at the start of every substep (explicit; calibration harness:
  // docs/calibration.md). Either way friction_on = false removes it.
  enum class FrictionLaw { kFrictionloss, kTanh };
  FrictionLaw friction_law = FrictionLaw::kFrictionloss;
  // v_s [rad/s] per device dof of kTanh (empty: 0.01 each; 0 = sign); phantom_device_config
  // sets the model's coulomb_smoothing_rad_s. The law is the model's own (phantom_joint_friction).
  VecX coulomb_velocity;
  // The smooth sign per device dof of kTanh (empty: tanh each); phantom_device_config sets the
  // model's coulomb_sign.
  std::vector<CoulombSign> coulomb_sign;
  // Servo clock.
  TickJitter jitter;
};

// Phantom Premium 1.5/6DoF defaults for the quantities above (docs/device_facts.md §3).
VecX phantom_drive_ratios();  // (13.3, 11.2, 11.2, 1, 1, 1)
VecX phantom_tau_max();       // (0.400, 0.350, 0.200, 0.188, 0.188, 0.048) N m

// Encoder quantum Delta_i = 2 pi / (quadrature counts_per_rev ratio_i).
VecX encoder_quantum(int counts_per_rev, int quadrature, const VecX& drive_ratio);

class SimulatedPhantom : public Device {
 public:
  // Compiles the plant, applies the configuration, starts at q0 (device coordinates) at rest,
  // t = 0. Throws InputError on a bad plant or configuration (the message names the field).
  SimulatedPhantom(const MujocoPlant& plant, SimulatedDeviceConfig config, const VecX& q0);
  ~SimulatedPhantom() override;

  // Device interface.
  const DeviceCapabilities& capabilities() const override { return caps_; }
  const DeviceLimits& limits() const override { return limits_; }
  void read(DeviceSample& out) const override;
  void write(const VecX& tau) override;
  void advance() override;
  const VecX& applied_torque() const override { return tau_applied_; }
  std::uint32_t faults() const override { return faults_; }
  void clear_faults() override { faults_ = kFaultNone; }

  // Attaches the scripted hand (its mass and inertia join the tip body) or, with nullptr,
  // releases the device. The hand must outlive its attachment.
  void set_hand(const ScriptedHand* hand);
  const ScriptedHand* hand() const { return hand_; }

  // Called after every substep with the physics time and the MuJoCo state (tests: ZOH).
  using SubstepHook = std::function<void(double t, const mjModel_* m, const mjData_* d)>;
  void set_substep_hook(SubstepHook hook) { hook_ = std::move(hook); }

  // Ground truth (not visible to a real driver).
  const VecX& true_q() const { return q_true_; }    // unquantised joint angles [rad]
  const VecX& true_qd() const { return qd_true_; }  // joint velocities [rad/s]
  double physics_time() const;                      // [s]
  double last_tick() const { return T_last_; }      // T_k of the last advance() [s]
  int last_substeps() const { return n_sub_last_; }
  Pose tip_pose() const;                               // tip pose now
  Vec6 tip_twist() const;                              // V = [v (world); w (body)] now
  const Vec6& hand_wrench() const { return F_hand_; }  // hand's spring-damper F at the sample
  // The joint torques of the hand-tool contact wrench, time-averaged over the last tick:
  // G^T (J_p^T f + J_r^T R tau) of the spring-damper wrench minus the hand's own inertial
  // reaction G^T (J_p^T m_h dv + J_r^T J_h dw) / T (its mass rides on the tip). This is what the
  // device feels from the human: the observer's ground truth. At rest it is G^T J^T F.
  const VecX& hand_joint_torque() const { return tau_hand_avg_; }
  // Mechanical energy of the plant (kinetic + gravitational potential) now [J].
  double energy() const;
  // Encoder quantum per joint [rad] (0 when quantisation is off).
  const VecX& quantum() const { return caps_.encoder_quantum; }
  // The motors' thermal state (inactive unless config.torque_limit is kThermal).
  const MotorThermal& motor_thermal() const { return thermal_; }

  const mjModel_* model() const;
  const SimulatedDeviceConfig& config() const { return cfg_; }

 private:
  double draw_tick();
  void update_tip_kinematics();  // kinematics at the current qpos; fills tip pose/Jacobians
  void apply_hand(double t);     // computes F_hand_ and sets xfrc_applied
  void refresh_truth();
  void sample_encoders();
  void merge_hand_mass(bool attach);
  void save_hand_substep();
  void subtract_hand_inertia(double T);

  MujocoPlant plant_;
  SimulatedDeviceConfig cfg_;
  std::unique_ptr<MujocoHandle> h_;
  mjData_* scratch_ = nullptr;  // energy evaluation
  DeviceCapabilities caps_;
  DeviceLimits limits_;
  VelocityEstimator vel_;
  MotorThermal thermal_;
  std::mt19937_64 rng_;
  std::size_t trace_index_ = 0;
  SubstepHook hook_;
  const ScriptedHand* hand_ = nullptr;

  // Saved inertia of the tip body (restored when the hand is released).
  double body_mass0_ = 0.0;
  double body_ipos0_[3] = {0, 0, 0};
  double body_iquat0_[4] = {1, 0, 0, 0};
  double body_inertia0_[3] = {0, 0, 0};
  unsigned char body_sameframe0_ = 0, body_simple0_ = 0;
  std::vector<int> dof_simplenum0_;

  VecX q_true_, qd_true_, q_meas_, q_meas_prev_, tau_applied_, tau_hand_avg_, tau_hand_sub_;
  VecX tau_hand_inertia_;
  VecX coulomb_tanh_;  // f_c per device dof of FrictionLaw::kTanh (else empty)
  VecX Q_tree_;        // nv scratch
  double t_sample_ = 0.0, t_prev_sample_ = 0.0, T_last_ = 0.0;
  int n_sub_last_ = 0;
  std::uint32_t faults_ = kFaultNone;
  Vec6 F_hand_ = Vec6::Zero();
  Pose tip_;
  std::vector<double> jacp_, jacr_;  // 3 x nv each, row-major
  std::vector<double> jacp_prev_, jacr_prev_;
  Vec6 V_world_ = Vec6::Zero(), V_world_prev_ = Vec6::Zero();  // tip [v; w], both world
};

}  // namespace dentsim
