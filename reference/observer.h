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
//
// Input matched to the velocity estimate (ObserverInput; off by default = the thesis's form).
// A driver without a tachometer reports qd_k as a backward difference of the angles, often
// low-passed (device/velocity_estimator.h): qd_k = H(z) (q_k - q_k-1) / T_k. The momentum
// M qd_k then lags the true momentum while tau_k enters p_hat without that lag, so
//     f_hat = L / (s + L) (H f + (H - 1) u),   u = tau + beta,
// and when the command contains -f_hat (the passive decomposition's feed-forward (4.7)) the
// (H - 1) term closes a loop f_hat -> tau -> f_hat whose phase lag makes it unstable for
// L tau_H of order one (tau_H the delay of H: a few ms). Matching the input removes the loop.
// For a constant M and tick T, the mean velocity over a tick obeys exactly
//     M ((q_k+1 - q_k) - (q_k - q_k-1)) / T = T ((tau_k-1 + tau_k)/2 + f)   (ZOH tau, f constant)
// so the backward difference pairs with the torque averaged over the two ticks it spans, and a
// low-pass applied to qd must be applied to u as well (a linear filter commutes with the
// difference). With
//     u_k = beta_k + (tau_k-1 + tau_k)/2                     (match_backward_difference)
//     u_f,k = u_f,k-1 + a_k (u_k - u_f,k-1),  a_k = 1 - exp(-2 pi f_c T_k)   (lowpass_hz = f_c)
//     p_hat_k+1 = p_hat_k + T_k (u_f,k + f_hat_k)
// the estimate becomes f_hat = L / (s + L) H f: the human force seen through the same filter as
// the velocity, with no path from tau back to f_hat (exact for a constant M with beta = 0; beta
// is taken at t_k, the centre of the two ticks the difference spans). The observer starts as the
// estimator does, at rest: tau_-1 = -beta_0 (equilibrium before the start) and u_f = 0.
#pragma once

#include "reference/core/device_model.h"
#include "reference/core/lowpass.h"
#include "reference/core/params.h"
#include "reference/core/pipeline.h"
#include "reference/core/types.h"

namespace dentsim {

// ObserverInput (how u = tau + beta is matched to the velocity estimate) is in
// reference/core/params.h.

// The observer's step on model terms already evaluated at the new sample, shared by
// MomentumObserver (any n, VecX) and the tick's observe stage (Vec6, the device terms of the
// tick): Mqd = M(q_k+1) qd_k+1 and beta_next = beta(q_k+1, qd_k+1); tau is the torque held over
// the tick of length T that just ended. The state starts at rest (reset).
template <class V>
void momentum_observer_reset(MomentumObserverState<V>& s, const V& Mqd, const V& beta) {
  s.p_hat = Mqd;  // p = M(q) qd
  s.f_hat = V::Zero(Mqd.size());
  s.beta_prev = beta;
  s.tau_prev = -beta;  // at rest in equilibrium before the start
  s.u_f = V::Zero(Mqd.size());
  s.ready = true;
}

template <class V>
void momentum_observer_update(const V& L, const ObserverInput& in, MomentumObserverState<V>& s,
                              const V& Mqd, const V& beta_next, const V& tau, double T) {
  // u_k: thesis form (beta_k + beta_k+1)/2 + tau_k; matched to a backward difference,
  // beta_k + (tau_k-1 + tau_k)/2 (the triangle of the two ticks the difference spans, centred at
  // t_k). reset() sets tau_k-1 = -beta_0: the device was at rest in equilibrium before the start.
  V u = in.match_backward_difference ? V(s.beta_prev + 0.5 * (s.tau_prev + tau))
                                     : V(0.5 * (s.beta_prev + beta_next) + tau);
  if (in.lowpass_hz > 0.0) {
    // The velocity estimator's low-pass, applied to u; it starts settled at rest (u_f = 0), as
    // the estimator starts from qd = 0.
    const double a = lowpass_gain(in.lowpass_hz, T);
    s.u_f += a * (u - s.u_f);
    u = s.u_f;
  }
  s.tau_prev = tau;
  // p_hat_k+1 = p_hat_k + T (u_k + f_hat_k)                                        (3.8), §4.1.1
  s.p_hat += T * (u + s.f_hat);
  // f_hat_k+1 = L (M(q_k+1) qd_k+1 - p_hat_k+1)                                          §4.1.1
  s.f_hat = L.asDiagonal() * (Mqd - s.p_hat);
  s.beta_prev = beta_next;
}

// Throws std::invalid_argument naming the entry unless gain_L has `dof` finite positive gains and
// input.lowpass_hz is finite and >= 0 (MomentumObserver and the pipeline's model use it).
void validate_observer(const VecX& gain_L, int dof, const ObserverInput& input);

class MomentumObserver {
 public:
  // gain_L: the diagonal of L, one positive gain per joint [1/s]. The model must outlive the
  // observer. Throws std::invalid_argument for a wrong size, a non-positive gain or a negative
  // or non-finite lowpass_hz.
  MomentumObserver(const DeviceModel& model, VecX gain_L, ObserverInput input = {});

  // Starts at rest on the current sample: p_hat = M(q) qd, f_hat = 0.
  void reset(const VecX& q, const VecX& qd);
  // One tick: (q, qd) sampled at t_k+1, tau the joint torque held over the tick of length T > 0.
  // Returns f_hat_k+1. Throws std::logic_error before reset(), std::invalid_argument for wrong
  // sizes or T <= 0.
  const VecX& update(const VecX& q, const VecX& qd, const VecX& tau, double T);
  // The current joint-space estimate f_hat.
  const VecX& estimate() const { return s_.f_hat; }
  const VecX& gain() const { return L_; }
  const ObserverInput& input() const { return input_; }

  // beta(q, qd) = C^T qd - g - tau_f of (3.7).
  VecX beta(const VecX& q, const VecX& qd) const;

 private:
  const DeviceModel& model_;
  VecX L_;
  ObserverInput input_;
  MomentumObserverState<VecX> s_;
};

// The human wrench in maximal coordinates from the joint estimate: F1_hat = J1^T f_hat, with
// qd = J1 V1 (2.2), so that V1^T F1_hat = qd^T f_hat (thesis §4.1.1: "converted into maximal
// coordinates").
Vec6 joint_to_wrench(const Mat6& J1, const VecX& f_joint);

}  // namespace dentsim
