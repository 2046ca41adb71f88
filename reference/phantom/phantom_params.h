// Parameters of the Phantom Premium 1.5/6DoF device model and its model file (issue #3).
//
// One struct holds every number of the device: the parallelogram arm of Cavusoglu, Feygin &
// Tendick 2002 (lengths l1, l2, l3 [m], link masses [kg] and inertias [kg m^2]), the actuated
// 3-axis gimbal (geometry and inertia: not published, nominal values, identified by
// calibration/), the tool-tip offset, and per device joint j = 1..6: rotor inertia (armature)
// [kg m^2], viscous damping [N m s/rad], Coulomb friction [N m], joint limits [rad], torque limits
// [N m] and encoder counts per joint revolution. Sources of every default: docs/device_facts.md
// and docs/phantom.md.
//
// Frames (docs/phantom.md has a figure-in-words):
// - world {O}: origin at the shoulder (intersection of the yaw and shoulder axes), z up; at q = 0
//   the arm points along +x.
// - every link has its own frame; a body's inertial parameters (mass, CoM `com_m` in the body
//   frame, principal moments `inertia_kg_m2` about the CoM along the body axes) are given there.
//   Upper arm `be` and parallel link `c`: x = shoulder axis, z along the link (elbow at z = l1).
//   Forearm `a` and crank `df`: x = shoulder axis, y along the link (gimbal centre at y = l2).
//   Base: z = yaw axis. Gimbal bodies: aligned with the forearm frame at zero gimbal angles.
//
// The model file is JSON with the units in the key names; default_phantom_model_file() is the
// published Premium 1.5A set and documents the format by example (docs/phantom.md describes each
// key). Loading validates every field and the positive definiteness of M(q) over the joint-limit
// box; failures throw InputError naming the file and the field.
#pragma once

#include <array>
#include <string>

#include "reference/core/types.h"

namespace dentsim {

// Inertial parameters of one rigid body, in that body's frame.
enum class CoulombSign { kTanh, kErf };
const char* coulomb_sign_name(CoulombSign s);  // "tanh", "erf"

struct PhantomBody {
  double mass_kg = 0.0;
  Vec3 com_m = Vec3::Zero();          // centre of mass in the body frame [m]
  Vec3 inertia_kg_m2 = Vec3::Zero();  // principal moments about the CoM, body axes [kg m^2]

  bool operator==(const PhantomBody&) const = default;
};

// How the simulated device limits each joint's motor torque (model-file key "torque_limit",
// optional; docs/simulated_device.md "Motor torque limit"). kClamp (absent key, or
// {"model": "clamp"}): every tick's torque is clipped to joints.torque_limit_n_m, the
// OpenHaptics "max continuous" clamp. kThermal: clipped to peak_n_m, and a two-node thermal model
// of each motor (winding, housing; device/motor_thermal.h) lowers the limit once the winding would
// pass max_winding_temperature_c: back towards continuous_n_m (on_overheat "derate") or to a
// motor_temperature fault with zero torque (on_overheat "fault", as HDAPI's HD_WARM_MOTORS).
// The heat is P_j = P_cont,j (tau_j / continuous_n_m_j)^2 with P_cont,j = (T_max,j - T_amb) /
// (R_wh,j + R_ha,j): continuous_n_m is the torque whose steady-state winding sits at T_max.
enum class TorqueLimitModel { kClamp, kThermal };
enum class OnOverheat { kDerate, kFault };
struct MotorThermalParams {
  TorqueLimitModel model = TorqueLimitModel::kClamp;
  Vec6 peak_n_m = Vec6::Zero();                 // |tau_j| <= peak at every tick [N m]
  Vec6 continuous_n_m = Vec6::Zero();           // thermal rating at the joint [N m]
  Vec6 r_winding_housing_k_per_w = Vec6::Zero();  // R_wh [K/W]
  Vec6 r_housing_ambient_k_per_w = Vec6::Zero();  // R_ha [K/W]
  Vec6 tau_winding_s = Vec6::Zero();            // C_w R_wh [s]
  Vec6 tau_motor_s = Vec6::Zero();              // C_h R_ha [s]
  Vec6 max_winding_c = Vec6::Zero();            // T_max [deg C]
  double ambient_c = 25.0;                      // T_amb [deg C], also the initial temperature
  OnOverheat on_overheat = OnOverheat::kDerate;

  bool operator==(const MotorThermalParams&) const = default;
};

struct PhantomParams {
  std::string name;

  // Arm geometry (Cavusoglu 2002): l1 shoulder-elbow, l2 elbow-gimbal centre, l3 crank [m].
  double l1_m = 0.0;
  double l2_m = 0.0;
  double l3_m = 0.0;

  // Links (names as in Cavusoglu 2002).
  PhantomBody base;           // turret, turns with q1 (only its z inertia matters)
  PhantomBody upper_arm;      // `be`, turns with q2
  PhantomBody forearm;        // `a`, turns with q3 (absolute), hinged to be at the elbow
  PhantomBody crank;          // `df`, turns with q3, coaxial with the shoulder
  PhantomBody parallel_link;  // `c`, closes the parallelogram, parallel to be
  PhantomBody gimbal_yaw;     // q4, hinged to the forearm at the gimbal centre
  PhantomBody gimbal_pitch;   // q5
  PhantomBody gimbal_roll;    // q6, carries the stylus / handpiece

  // Gimbal geometry. Joint origins in the parent body frame (the yaw joint sits at the gimbal
  // centre, y = l2 in the forearm frame); joint axes (unit) in the joint's own body frame.
  Vec3 pitch_pos_m = Vec3::Zero();
  Vec3 roll_pos_m = Vec3::Zero();
  Vec3 yaw_axis = Vec3::UnitY();
  Vec3 pitch_axis = Vec3::UnitX();
  Vec3 roll_axis = Vec3::UnitZ();
  Vec3 tip_offset_m = Vec3::Zero();  // tool tip x1 in the roll body frame [m]; R1 = R_roll

  // Per device joint j = 1..6 (q1 yaw, q2 upper arm, q3 forearm, q4..q6 gimbal yaw, pitch, roll).
  Vec6 armature_kg_m2 = Vec6::Zero();         // reflected rotor inertia (+ link excess, docs)
  Vec6 damping_n_m_s_per_rad = Vec6::Zero();  // viscous b_j
  Vec6 coulomb_n_m = Vec6::Zero();            // Coulomb f_c,j
  // v_s per joint of the smooth sign s(qd / v_s); 0 = f_c sign(qd). The model file takes one
  // number (every joint) or six; it writes one number when all six are equal.
  Vec6 coulomb_smoothing_rad_s = Vec6::Zero();
  // The smooth sign per joint (phantom_joint_friction): tanh, or erf, the sign averaged over a
  // Gaussian velocity dither of std v_s / sqrt(2) (E[sign(v + n)] = erf(v / v_s)): what a joint
  // whose velocity dithers (quantised sensing, a light link) feels. Model file key
  // joints.coulomb_sign: "tanh" or "erf" (every joint) or six of them; optional, default tanh,
  // written only when a joint is not tanh (the files written before read the same).
  std::array<CoulombSign, 6> coulomb_sign{};
  Vec6 q_min_rad = Vec6::Constant(-1.0);
  Vec6 q_max_rad = Vec6::Constant(1.0);
  Vec6 torque_limit_n_m = Vec6::Zero();
  Vec6 encoder_counts_per_rev = Vec6::Zero();  // counts per joint revolution (after the capstan)
  // The motor torque limit model (key "torque_limit"; absent: kClamp at torque_limit_n_m).
  MotorThermalParams torque_limit;

  bool gravity_on = true;
  double gravity_m_s2 = 9.81;  // |g|, acting along -z of {O}

  bool operator==(const PhantomParams&) const = default;
};

// The torque the simulated device clips every tick's command to: torque_limit_n_m (kClamp) or
// the peak (kThermal). What a pipeline's and a safety chain's saturation should use.
Vec6 phantom_torque_clamp(const PhantomParams& p);
// The Premium 1.5A's motors as a thermal torque limit (Maxon RE 25 on the arm, docs/device_facts.md
// §3 "Motor thermal limit"): peak (1.716, 1.445, 1.445) N m, continuous (0.380, 0.320, 0.320) N m;
// the gimbal's peak = continuous = its torque_limit_n_m (no published peak).
MotorThermalParams phantom_thermal_torque_limit();

// The published Premium 1.5A set (Cavusoglu 2002 arm, drive train of docs/device_facts.md §3,
// nominal gimbal).
PhantomParams default_phantom_params();
// The shipped model file: phantom_params_to_text(default_phantom_params()).
std::string default_phantom_model_file();

// Reads and validates a model file; throws InputError naming `path` and the field.
PhantomParams load_phantom_params(const std::string& path);
// Parses and validates model-file text; `origin` names the source in error messages.
PhantomParams parse_phantom_params(const std::string& text, const std::string& origin);
// The model-file text of `p` (JSON, numbers with 17 significant digits: re-loads exactly).
std::string phantom_params_to_text(const PhantomParams& p);

// Physical validation (called by the loaders): positive masses, inertias positive and satisfying
// the triangle inequality, unit axes, ordered limits, non-negative friction, positive torque
// limits and encoder counts, and M(q) positive definite at `workspace_samples` deterministic
// points of the joint-limit box (its corners, centre and a fixed-seed sample). Throws InputError
// "<origin>: <field>: <what was expected>, got <value>".
void validate_phantom_params(const PhantomParams& p, const std::string& origin,
                             int workspace_samples = 256);

}  // namespace dentsim
