// Momentum-based human force observer (thesis §3.2, eqs (3.7)-(3.8); discrete form §4.1.1),
// over any DeviceModel (reference/core/device_model.h).
//
// Units: joint coordinates q [rad or m], torques [N m or N], gains L [1/s], tick T [s].
// Model: M(q) qdd + C(q, qd) qd + g(q) + tau_f(q, qd) = tau + f, f the human joint force.
// With the generalised momentum p = M(q) qd and dM/dt = C + C^T,
//     dp/dt = beta(q, qd) + tau + f,   beta = C^T(q, qd) qd - g(q) - tau_f(q, qd)      (3.7)
// (the thesis assumes g and tau_f compensated and writes C^T qd only; including them removes the
// bias they would cause). Observer (3.8) with f_hat = L (p - p_hat):
//     dp_hat/dt = beta + tau + f_hat  =>  f_hat = L / (s + L) f per joint (L diagonal).
// Discretisation (§4.1.1), one call per servo tick; tau_k is held over [t_k, t_k+1]:
//     p_hat_k+1 = p_hat_k + T_k ((beta_k + beta_k+1)/2 + tau_k + f_hat_k)
//     f_hat_k+1 = L (M(q_k+1) qd_k+1 - p_hat_k+1)
// The thesis evaluates beta once per tick (rectangle rule); the trapezoid on beta uses the
// sample already at hand and removes the O(T dbeta/dt / 2) bias of the rectangle rule.
// Step response: f_hat_k = f (1 - (1 - L T)^k), the sampled first-order lag; stable for
// 0 < L T < 2, monotone for L T <= 1. A model damping off by dB (model B_d + dB) biases the
// steady estimate by +dB qd. Derivation: docs/derivations/decomposition_and_observer.md.
#pragma once

#include "reference/core/device_model.h"
#include "reference/core/types.h"

namespace dentsim {

class MomentumObserver {
 public:
  // gain_L: the diagonal of L, one positive gain per joint [1/s]. The model must outlive the
  // observer. Throws std::invalid_argument for a wrong size or a non-positive gain.
  MomentumObserver(const DeviceModel& model, VecX gain_L);

  // Starts at rest on the current sample: p_hat = M(q) qd, f_hat = 0.
  void reset(const VecX& q, const VecX& qd);
  // One tick: (q, qd) sampled at t_k+1, tau the joint torque held over the tick of length T > 0.
  // Returns f_hat_k+1. Throws std::logic_error before reset(), std::invalid_argument for wrong
  // sizes or T <= 0.
  const VecX& update(const VecX& q, const VecX& qd, const VecX& tau, double T);
  // The current joint-space estimate f_hat.
  const VecX& estimate() const { return f_hat_; }
  const VecX& gain() const { return L_; }

  // beta(q, qd) = C^T qd - g - tau_f of (3.7).
  VecX beta(const VecX& q, const VecX& qd) const;

 private:
  const DeviceModel& model_;
  VecX L_;
  VecX p_hat_;
  VecX f_hat_;
  VecX beta_prev_;
  bool ready_ = false;
};

// The human wrench in maximal coordinates from the joint estimate: F1_hat = J1^T f_hat, with
// qd = J1 V1 (2.2), so that V1^T F1_hat = qd^T f_hat (thesis §4.1.1: "converted into maximal
// coordinates").
Vec6 joint_to_wrench(const Mat6& J1, const VecX& f_joint);

}  // namespace dentsim
