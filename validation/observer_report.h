// How well the momentum observer (reference/observer.h, thesis (3.7)-(3.8), §4.1.1) estimates the
// scripted hand's joint torques on the simulated Phantom, with the true device model and with a
// model whose inertia and damping are off by a factor (1 + model_error) (issue #3).
//
// Experiment (all times in s, torques in N m, joint coordinates q1..q6):
//   - the device starts at rest at q_hold; the motors render gravity compensation (the observer's
//     model g(q)) plus a joint-space hold spring-damper tau = g(q) + K_p (q_hold - q) - K_d qd
//     (q, qd as the driver reports them: quantised, velocity estimated), saturated by the device;
//   - the hand (default literature impedance) holds the initial tip pose; at t_step it adds a
//     feed-forward force step f_step (world) and keeps it: the device settles where the hold
//     spring balances the hand;
//   - from t_move to t_end the hand's reference moves back and forth along x (triangle wave,
//     amplitude move_amplitude, period move_period): the joints move, so inertia and damping
//     matter.
// Ground truth: the joint torques of the hand-tool contact wrench (spring-damper wrench minus
// the hand's own inertial reaction, its mass riding on the tip), averaged over each tick: the
// simulated device's hand_joint_torque(). The observer's f_hat_k (after the sample at t_k) is
// compared with the truth averaged over the tick that ended at t_k. The true model is the
// analytic PhantomModel of the same model file (without Coulomb friction when the simulated
// device has none).
// Measures per model:
//   - steady: median signed error f_hat - f_true per joint over [t_move - settle_window, t_move)
//     (median: with quantised encoders the hold settles into a limit cycle one quantum wide whose
//     count toggles give short velocity spikes, and a spike cut by the window edge would bias a
//     mean by ~1e-4 N m);
//   - lag: on the joint with the largest step in f_true, 1/L_fit, L_fit the gain of the
//     first-order lag of f_true that best fits f_hat over [t_step, t_step + settle_window)
//     (least squares; the ideal observer L/(s+L) gives 1/L whatever shape f_true has);
//   - moving, over [t_move + 1/4 period, t_end): RMS error f_hat - f_true per joint, and the
//     error beyond the observer's own lag, f_hat - LPF_L(f_true) (LPF_L the sampled first-order
//     lag an ideal observer would produce): its mean (the bias a model error causes) and RMS.
//     A damping error dB biases by +dB qd, i.e. along the motion: the mean of
//     sign(qd) (f_hat - LPF_L(f_true)) measures it where a symmetric motion averages the plain
//     mean out.
// Invisible to any model: the joint stiction (MuJoCo frictionloss holds a joint at rest with any
// torque up to f_c), which bounds the steady error when the device has friction.
// Any set of named observer models can be compared on the same simulated device
// (run_observer_models): each model both compensates gravity in the motors and runs the observer,
// as a user's model would (the calibration's end-to-end check, docs/calibration.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "device/scripted_hand.h"
#include "device/simulated_phantom.h"
#include "reference/core/device_model.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

// A device model with the inertia (M and C) scaled by inertia_scale and the friction torque
// (viscous and Coulomb) by damping_scale; gravity unchanged. The base must outlive it.
class ScaledDeviceModel : public DeviceModel {
 public:
  ScaledDeviceModel(const DeviceModel& base, double inertia_scale, double damping_scale)
      : base_(base), s_m_(inertia_scale), s_b_(damping_scale) {}
  int dof() const override { return base_.dof(); }
  MatX mass_matrix(const VecX& q) const override { return s_m_ * base_.mass_matrix(q); }
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override {
    return s_m_ * base_.coriolis_matrix(q, qd);
  }
  VecX gravity(const VecX& q) const override { return base_.gravity(q); }
  VecX friction_torque(const VecX& q, const VecX& qd) const override {
    return s_b_ * base_.friction_torque(q, qd);
  }

 private:
  const DeviceModel& base_;
  double s_m_, s_b_;
};

struct ObserverReportConfig {
  double gain_L = 100.0;        // L [1/s], every joint
  double model_error = 0.2;     // relative error of the perturbed model's inertia and damping
  bool device_friction = true;  // Coulomb friction (stiction) on in the simulated device
  // Test harness check: exact joint angles and velocities (no quantisation, no estimator), so
  // that only the model enters the estimate.
  bool ideal_sensing = false;
  double t_step = 1.0;
  double t_move = 3.0;
  double t_end = 5.0;
  double settle_window = 0.5;
  Vec3 f_step = Vec3(0.0, 0.0, -1.0);                                    // [N], world
  double move_amplitude = 0.02;                                          // [m]
  double move_period = 1.0;                                              // [s]
  Vec6 K_p = (Vec6() << 2.0, 2.0, 2.0, 0.05, 0.05, 0.02).finished();     // [N m/rad]
  Vec6 K_d = (Vec6() << 0.01, 0.01, 0.01, 1e-4, 1e-4, 5e-5).finished();  // [N m s/rad]
  HandImpedance hand;  // the operator (literature defaults, scripted_hand.h)
  TickJitter jitter;   // default: constant 1 ms
  // The implementation evaluating the observer's device models (fast/registry.h): "reference"
  // (PhantomModel) or "fast" (fast::PhantomModel, the fast pipeline's device terms).
  std::string pipeline = "reference";
};

struct ObserverRun {
  std::string model;              // "true", "perturbed" or the name given to run_observer_models
  VecX steady_error;              // median f_hat - f_true per joint, hold phase [N m]
  double steady_error_max = 0.0;  // max |steady_error| [N m]
  int lag_joint = 0;              // joint (0-based) the lag is measured on
  double lag_s = 0.0;             // measured lag [s]
  VecX moving_bias;  // mean of f_hat - (first-order lag L of f_true) per joint, moving [N m]
  // mean of sign(qd_j) (f_hat - LPF_L(f_true))_j: a damping error dB biases by +dB qd, i.e.
  // along the motion, which a symmetric motion averages out of the plain mean [N m]
  VecX moving_bias_along_motion;
  VecX moving_rms;             // RMS error per joint, moving phase [N m]
  VecX moving_rms_beyond_lag;  // RMS of f_hat - (first-order lag L of f_true), moving [N m]
  VecX moving_truth_rms;       // RMS of f_true per joint, moving phase [N m] (signal size)
  VecX step_size;              // f_true(after) - f_true(before) per joint [N m]
};

struct ObserverReport {
  ObserverReportConfig config;
  double expected_lag_s = 0.0;    // 1/L
  VecX device_coulomb;            // f_c per joint of the simulated device [N m] (0 if off)
  std::vector<ObserverRun> runs;  // true model, then the perturbed model (or the named models)
  bool scaled_model_run = false;  // runs[1] is the true model scaled by 1 + config.model_error
};

// An observer model under a name (the model must outlive the call).
struct NamedObserverModel {
  std::string name;
  const DeviceModel* model = nullptr;
};

// The Phantom model of `params` as the named implementation evaluates it ("reference":
// PhantomModel, "fast": fast::PhantomModel). Throws InputError for another name.
std::unique_ptr<DeviceModel> observer_device_model(const PhantomParams& params,
                                                   const std::string& pipeline);

// The true model of the simulated device of `params` (the analytic PhantomModel's parameters):
// without Coulomb friction when config.device_friction is off.
PhantomParams observer_true_params(const PhantomParams& params, const ObserverReportConfig& config);

// Runs the experiment on the simulated Phantom of `params` (the true model is the analytic
// PhantomModel of the same params). Deterministic (the jitter is seeded).
ObserverReport run_observer_report(const PhantomParams& params, const ObserverReportConfig& config);

// The same experiment on the simulated Phantom of `params` with each of `models` in turn (gravity
// compensation and observer), in the order given; config.model_error is not used. Throws
// InputError on a bad config, an empty list, an empty or repeated name, a null model or a model
// that is not 6-DoF.
ObserverReport run_observer_models(const PhantomParams& params, const ObserverReportConfig& config,
                                   const std::vector<NamedObserverModel>& models);

// The report as JSON text and as a Markdown table (docs/simulated_device.md).
std::string observer_report_json(const ObserverReport& r);
std::string observer_report_table(const ObserverReport& r);

}  // namespace dentsim
