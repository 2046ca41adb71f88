#include "reference/observer.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "reference/core/lowpass.h"

namespace dentsim {
namespace {

void require_size(const VecX& v, int n, const char* what) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string("MomentumObserver: ") + what + " has " +
                                std::to_string(v.size()) + " entries, expected " +
                                std::to_string(n));
  }
}

}  // namespace

MomentumObserver::MomentumObserver(const DeviceModel& model, VecX gain_L, ObserverInput input)
    : model_(model), L_(std::move(gain_L)), input_(input) {
  require_size(L_, model_.dof(), "gain_L");
  for (int i = 0; i < L_.size(); ++i) {
    if (!(L_(i) > 0.0) || !std::isfinite(L_(i))) {
      throw std::invalid_argument("MomentumObserver: gain_L[" + std::to_string(i) +
                                  "] must be a finite positive gain [1/s], got " +
                                  std::to_string(L_(i)));
    }
  }
  if (!(input_.lowpass_hz >= 0.0) || !std::isfinite(input_.lowpass_hz)) {
    throw std::invalid_argument("MomentumObserver: input lowpass_hz must be finite and >= 0, got " +
                                std::to_string(input_.lowpass_hz));
  }
  f_hat_ = VecX::Zero(L_.size());
}

VecX MomentumObserver::beta(const VecX& q, const VecX& qd) const {
  // (3.7): dp/dt = C^T qd - g - tau_f + tau + f
  return model_.coriolis_matrix(q, qd).transpose() * qd - model_.gravity(q) -
         model_.friction_torque(q, qd);
}

void MomentumObserver::reset(const VecX& q, const VecX& qd) {
  require_size(q, model_.dof(), "q");
  require_size(qd, model_.dof(), "qd");
  p_hat_ = model_.mass_matrix(q) * qd;  // p = M(q) qd
  f_hat_ = VecX::Zero(model_.dof());
  beta_prev_ = beta(q, qd);
  tau_prev_ = -beta_prev_;
  u_f_ = VecX::Zero(model_.dof());
  ready_ = true;
}

const VecX& MomentumObserver::update(const VecX& q, const VecX& qd, const VecX& tau, double T) {
  if (!ready_) throw std::logic_error("MomentumObserver: update() before reset()");
  require_size(q, model_.dof(), "q");
  require_size(qd, model_.dof(), "qd");
  require_size(tau, model_.dof(), "tau");
  if (!(T > 0.0)) {
    throw std::invalid_argument("MomentumObserver: tick length T must be > 0, got " +
                                std::to_string(T));
  }
  const VecX beta_next = beta(q, qd);
  // u_k: thesis form (beta_k + beta_k+1)/2 + tau_k; matched to a backward difference,
  // beta_k + (tau_k-1 + tau_k)/2 (the triangle of the two ticks the difference spans, centred at
  // t_k). reset() sets tau_k-1 = -beta_0: the device was at rest in equilibrium before the start.
  VecX u = input_.match_backward_difference ? VecX(beta_prev_ + 0.5 * (tau_prev_ + tau))
                                             : VecX(0.5 * (beta_prev_ + beta_next) + tau);
  if (input_.lowpass_hz > 0.0) {
    // The velocity estimator's low-pass, applied to u; it starts settled at rest (u_f = 0), as
    // the estimator starts from qd = 0.
    const double a = lowpass_gain(input_.lowpass_hz, T);
    u_f_ += a * (u - u_f_);
    u = u_f_;
  }
  tau_prev_ = tau;
  // p_hat_k+1 = p_hat_k + T (u_k + f_hat_k)                                        (3.8), §4.1.1
  p_hat_ += T * (u + f_hat_);
  // f_hat_k+1 = L (M(q_k+1) qd_k+1 - p_hat_k+1)                                          §4.1.1
  f_hat_ = L_.asDiagonal() * (model_.mass_matrix(q) * qd - p_hat_);
  beta_prev_ = beta_next;
  return f_hat_;
}

Vec6 joint_to_wrench(const Mat6& J1, const VecX& f_joint) {
  if (f_joint.size() != 6) {
    throw std::invalid_argument("joint_to_wrench: f_joint has " + std::to_string(f_joint.size()) +
                                " entries, expected 6");
  }
  return J1.transpose() * f_joint;
}

}  // namespace dentsim
