// The scripted human operator of every experiment: a mass-spring-damper impedance gripping the
// tool tip and following a position profile, a force profile, or both.
//
// Wrench the hand applies to the tool at its tip, F = [f (world {O}); tau (tip body frame {B})]
// (docs/conventions.md "Frames", dual to V = [v (world); w (body)]):
//     f   = f_ff(t) + K_h (x_ref(t) - x) + B_h (v_ref(t) - v)                      [N]
//     tau = tau_ff(t) + k_hw log(R^T R_ref) - b_hw w                                [N m]
// with x, R the tip pose, v (world) and w (body) its twist. log(R^T R_ref) is the body-frame
// rotation vector from the tip to the reference orientation (so3_spring_vector, (2.11)-(2.13)).
// The hand's mass m_h (and rotational inertia J_h about the tip) moves rigidly with the tool:
// the simulated device adds it to the tip body (SimulatedPhantom::set_hand), so it is part of
// the plant, not of F. Together: Z_h(s) = m_h s + B_h + K_h / s about the reference.
//
// Defaults (docs/simulated_device.md): translational m_h = 0.554 kg, B_h = 6.45 N s/m,
// K_h = 135 N/m, the mass-damper-spring fit of a human arm holding a haptic device reported in
// "Haptic perception of force magnitude and its relation to postural arm dynamics in 3D",
// Sci. Rep. 5:18004 (2015), Fig. 3 caption (the example trial). The rotational values are an
// assumption of ours (no published pen-grasp value at hand), chosen so that the rotational corner
// frequency sqrt(k_hw/J_h) = 50 rad/s is comparable to the translational one. Stylus-grasp
// models on a Phantom Premium 1.5A: Fu & Cavusoglu, "Human arm-and-hand dynamics model with
// variability analyses for a stylus-based haptic interface", IEEE Trans. SMC-B.
#pragma once

#include <vector>

#include "reference/core/types.h"

namespace dentsim {

struct HandImpedance {
  double mass = 0.554;    // m_h [kg], added at the tip
  double inertia = 2e-4;  // J_h [kg m^2], isotropic about the tip (assumed)
  double k_lin = 135.0;   // K_h [N/m]
  double b_lin = 6.45;    // B_h [N s/m]
  double k_ang = 0.5;     // k_hw [N m/rad] (assumed)
  double b_ang = 0.005;   // b_hw [N m s/rad] (assumed)
};

// One keyframe of the profile; values are interpolated linearly between keyframes and held
// before the first and after the last.
struct HandKeyframe {
  double t = 0.0;                 // [s]
  Vec3 x_ref = Vec3::Zero();      // reference tip position [m] (world)
  Vec6 wrench_ff = Vec6::Zero();  // feed-forward wrench [N; N m] = [f (world); tau (body)]
};

class ScriptedHand {
 public:
  // Throws InputError if the keyframes are empty, their times are not strictly increasing or
  // not finite, or an impedance value is negative or not finite.
  ScriptedHand(HandImpedance impedance, std::vector<HandKeyframe> profile,
               Mat3 R_ref = Mat3::Identity());

  // A hand holding x_ref (and R_ref) still with no feed-forward wrench.
  static ScriptedHand holding(HandImpedance impedance, const Pose& pose);

  const HandImpedance& impedance() const { return z_; }
  const std::vector<HandKeyframe>& profile() const { return profile_; }
  const Mat3& R_ref() const { return R_ref_; }

  // x_ref(t), v_ref(t) = dx_ref/dt (slope of the current segment; 0 outside) and f_ff(t).
  Vec3 x_ref(double t) const;
  Vec3 v_ref(double t) const;
  Vec6 wrench_ff(double t) const;

  // The hand's wrench F = [f (world); tau (body)] on the tool at time t, given the tip pose and
  // twist V = [v (world); w (body)]. No allocation.
  Vec6 wrench(const Pose& tip, const Vec6& V, double t) const;

 private:
  // Index i of the segment [t_i, t_i+1) containing t, or -1 before / size-1 after.
  int segment(double t) const;

  HandImpedance z_;
  std::vector<HandKeyframe> profile_;
  Mat3 R_ref_;
};

}  // namespace dentsim
