// MJCF (MuJoCo 2.2.2) model of the Phantom Premium 1.5/6DoF, generated from the device model file
// (reference/phantom/phantom_params.h): one source of truth, never hand-copied (issue #3).
//
// The generator walks the same kinematic tree as the analytic model (phantom_tree<double>,
// reference/phantom/phantom_model.h): body i at pos[i] with quat(rot0[i]) in its parent, a hinge
// about axis[i], an explicit <inertial> (mass, CoM, diagonal inertia; no inertia from geoms).
// The parallelogram is a real closed chain (docs/device_facts.md §4, MuJoCo 2.2.2): tree
// base(q1) -> upper_arm(q2) -> forearm(elbow = q3 - q2) -> gimbal yaw/pitch/roll (q4..q6), and
// base -> crank(q3) -> parallel_link(link_c = q2 - q3), closed by two linear equalities:
//   <joint joint1="link_c" joint2="elbow" polycoef="0 -1 0 0 0"/>  (link_c = -elbow)
//   <tendon tendon1="parallelogram"/>, fixed tendon q3 - q2 - elbow = 0.
// Device joint j is tree joint phantom_actuated_tree_joint(j) and carries the armature, viscous
// damping, Coulomb friction (frictionloss), limits and a motor (gear 1, ctrl = torque [N m],
// saturated at the torque limit). Site "tip" is the tool tip x1 on the roll body (R1 = its frame).
#pragma once

#include <array>
#include <string>

#include "reference/phantom/phantom_params.h"

namespace dentsim {

struct PhantomMjcfOptions {
  double timestep_s = 1e-4;
  std::string integrator = "RK4";  // "Euler", "RK4" or "implicit"
  bool joint_limits = true;        // range + limited="true" on the device joints
  bool joint_damping = true;       // viscous damping from the model file
  bool joint_friction = true;      // Coulomb friction as MuJoCo frictionloss
  bool torque_saturation = true;   // ctrlrange = +-torque limit
  // Equality-constraint reference (time constant [s], damping ratio). MuJoCo's default is
  // (0.02, 1); a stiffer closure keeps the chain closed tighter (docs/phantom.md).
  double equality_timeconst_s = 0.002;
  double equality_dampratio = 1.0;
  // Equality impedance d (solimp dmin = dmax): MuJoCo's constraints are soft, and a fraction
  // 1 - d of the unconstrained acceleration leaks through them; 0.9999 is MuJoCo's maximum
  // (default 0.9 .. 0.95, which lets the chain open under gravity).
  double equality_impedance = 0.9999;
};

// MJCF names: joints per tree body (theta_0..theta_7), actuators per device joint, the tip site.
inline constexpr std::array<const char*, 8> kPhantomMjcfJoints = {"q1",     "q2", "elbow", "q3",
                                                                  "link_c", "q4", "q5",    "q6"};
inline constexpr std::array<const char*, 6> kPhantomMjcfMotors = {"tau1", "tau2", "tau3",
                                                                  "tau4", "tau5", "tau6"};
inline constexpr const char* kPhantomMjcfTipSite = "tip";

std::string phantom_mjcf(const PhantomParams& params, const PhantomMjcfOptions& options = {});

}  // namespace dentsim
