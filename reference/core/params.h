// Parameters and states of the pipeline, shared by reference/ and fast/.
// Symbols follow the thesis; units are SI unless the name says otherwise.
#pragma once

#include <string>
#include <vector>

#include "reference/core/types.h"

namespace dentsim {

// Virtual proxy (thesis §2.1.2, (2.3)-(2.5)): a rigid body with its centre of mass at the tool tip.
struct ProxyParams {
  double mass = 0.05;                              // m [kg]
  Mat3 inertia = Mat3::Identity() * 2e-5;          // J, body frame [kg m^2]
  double damping_lin = 0.0;                        // b_x [N s/m] (isotropic)
  double damping_ang = 0.0;                        // b_w [N m s/rad] (isotropic)
  // Keep the gyroscopic term C_k = diag(0, -S(J w_k)) of (2.8). The thesis drops it (as graphics
  // codes do); it is skew, so it does no work and PMI stays passive either way.
  bool gyroscopic = false;

  Mat6 M() const { return block_diag(mass * Mat3::Identity(), inertia); }         // M_2 (4.2)
  Mat6 B() const {                                                                 // B_2 (4.2)
    return block_diag(damping_lin * Mat3::Identity(), damping_ang * Mat3::Identity());
  }
};

// Proxy state at the start of tick k.
struct ProxyState {
  Pose pose;                        // x_2,k, R_2,k
  Vec6 V = Vec6::Zero();            // V_2,k = [v (world); w (body)]
  Vec6 V_hat_prev = Vec6::Zero();   // V_hat_2,k-1, used by the device-side coupling (4.3)-(4.4)
};

// Virtual coupling gains (2.9)-(2.14): K_vc = diag(k_x I, k_w I), B_vc = diag(b_x I, b_w I).
struct CouplingGains {
  double k_lin = 400.0;    // k_vc,x [N/m]
  double k_ang = 0.3;      // k_vc,w [N m/rad]
  double b_lin = 2.0;      // b_vc,x [N s/m]
  double b_ang = 0.002;    // b_vc,w [N m s/rad]
};

// One contact of the proxy with the tooth (§2.3): x_o the point on the tooth surface (world), n the
// unit outward surface normal (world), r the contact point on the proxy in the proxy body frame
// (x_c = x_2 + R_2 r), depth = delta_k = n^T (x_o - x_c) >= 0 when penetrating (recomputed by the
// contact stage from the pose; the stored value is what collision reported), stiffness K_tooth
// [N/m] and damping B_tooth [N s/m] of the material, and weight w >= 0: the members of one
// contact set are blended with weights normalised to sum 1 (docs/contact.md), so reporting one
// geometric contact N times does not make it N times stiffer.
struct Contact {
  Vec3 x_o = Vec3::Zero();
  Vec3 n = Vec3::UnitZ();
  Vec3 r = Vec3::Zero();
  double depth = 0.0;
  double stiffness = 0.0;
  double damping = 0.0;
  double weight = 1.0;
  int material = 0;
};

// Coulomb friction (2.20)-(2.22).
struct FrictionParams {
  bool enabled = false;
  double mu = 0.3;   // friction coefficient: |f_t| <= mu |f_n|
};

// Desired locked-system dynamics of a tool (thesis §3.1.2): M_d dv_L/dt + D_d v_L = F_L.
struct ToolDynamics {
  std::string name;
  Mat6 M_d = Mat6::Identity();
  Mat6 D_d = Mat6::Zero();
};

// The rendering method (docs/design.md "One servo tick").
enum class Method {
  kExplicitVc,   // standard virtual coupling, explicit Euler proxy (the thesis's baseline)
  kPmiVc,        // PMI proxy + PMI virtual coupling (§2)
  kPmiPd,        // PMI + passive decomposition + momentum observer (§3)
};

const char* method_name(Method m);
// Parses "explicit", "pmi" or "pmi-pd"; throws std::invalid_argument naming the value otherwise.
Method parse_method(const std::string& s);

// How the momentum observer's known input u = tau + beta is matched to the velocity estimate
// (reference/observer.h). The default (both off) is the thesis's discretisation.
struct ObserverInput {
  bool match_backward_difference = false;  // u uses (tau_k-1 + tau_k)/2
  double lowpass_hz = 0.0;                 // > 0: u low-passed like qd (first order, f_c [Hz])
};

// The encoder Kalman filter's model of what it does not know (reference/encoder_kalman.h).
struct EncoderKalmanParams {
  // The force the model does not know, per axis [N]: the observer's accuracy target (issue #29:
  // 0.05 N). The quiet measures change little between 0.05 and 1 N
  // (docs/derivations/quiet_stiffness.md).
  double force_sigma_n = 0.05;
  double grip_lever_m = 0.01;  // a pen grip's lever for the hand's torque [m]
  // The prediction's acceleration includes the model's joint friction tau_f (true, the default)
  // or leaves it to the process noise (false; scene key method.encoder_kalman_friction):
  // docs/derivations/quiet_stiffness.md 8.6.
  bool model_friction = true;
  // With model_friction: the friction is set-valued (stick-slip) instead of the model's smooth
  // tau_f at the filter's velocity: Coulomb impulses in [-f_c T, f_c T] solved across the coupled
  // joints with the viscous part implicit (encoder_stick_slip_velocity in
  // reference/encoder_kalman.h; scene key method.encoder_kalman_friction_model "stick_slip";
  // docs/derivations/quiet_stiffness.md 8.7). Needs the device model's coefficients
  // (SixDofDeviceModel::joint_friction_coefficients).
  bool stick_slip = false;
};

// The sensorless grip detector's band, power filter and CUSUM thresholds
// (reference/grip_detector.h).
struct GripDetectorParams {
  double highpass_hz = 4.0;             // band of the statistic: first-order high-pass [Hz]
  double lowpass_hz = 20.0;             // and first-order low-pass [Hz] on h0, h1
  double power_time_constant_s = 0.05;  // first-order low-pass on the band powers [s]
  double release_threshold = 0.4;       // switch to released when s > this [N^2/kg]
  double grip_threshold = 0.02;         // switch to gripped when s < -this [N^2/kg]
  double evidence = 0.02;               // G: the CUSUM's decision level [N^2 s/kg]
  bool start_gripped = true;
};

}  // namespace dentsim
