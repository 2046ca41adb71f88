#include "reference/observer.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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

void validate_observer(const VecX& gain_L, int dof, const ObserverInput& input) {
  require_size(gain_L, dof, "gain_L");
  for (int i = 0; i < gain_L.size(); ++i) {
    if (!(gain_L(i) > 0.0) || !std::isfinite(gain_L(i))) {
      throw std::invalid_argument("MomentumObserver: gain_L[" + std::to_string(i) +
                                  "] must be a finite positive gain [1/s], got " +
                                  std::to_string(gain_L(i)));
    }
  }
  if (!(input.lowpass_hz >= 0.0) || !std::isfinite(input.lowpass_hz)) {
    throw std::invalid_argument("MomentumObserver: input lowpass_hz must be finite and >= 0, got " +
                                std::to_string(input.lowpass_hz));
  }
}

MomentumObserver::MomentumObserver(const DeviceModel& model, VecX gain_L, ObserverInput input)
    : model_(model), L_(std::move(gain_L)), input_(input) {
  validate_observer(L_, model_.dof(), input_);
  s_.f_hat = VecX::Zero(L_.size());
}

VecX MomentumObserver::beta(const VecX& q, const VecX& qd) const {
  // (3.7): dp/dt = C^T qd - g - tau_f + tau + f
  return model_.coriolis_matrix(q, qd).transpose() * qd - model_.gravity(q) -
         model_.friction_torque(q, qd);
}

void MomentumObserver::reset(const VecX& q, const VecX& qd) {
  require_size(q, model_.dof(), "q");
  require_size(qd, model_.dof(), "qd");
  const VecX Mqd = model_.mass_matrix(q) * qd;
  momentum_observer_reset<VecX>(s_, Mqd, beta(q, qd));
}

const VecX& MomentumObserver::update(const VecX& q, const VecX& qd, const VecX& tau, double T) {
  if (!s_.ready) throw std::logic_error("MomentumObserver: update() before reset()");
  require_size(q, model_.dof(), "q");
  require_size(qd, model_.dof(), "qd");
  require_size(tau, model_.dof(), "tau");
  if (!(T > 0.0)) {
    throw std::invalid_argument("MomentumObserver: tick length T must be > 0, got " +
                                std::to_string(T));
  }
  const VecX Mqd = model_.mass_matrix(q) * qd;
  momentum_observer_update<VecX>(L_, input_, s_, Mqd, beta(q, qd), tau, T);
  return s_.f_hat;
}

Vec6 joint_to_wrench(const Mat6& J1, const VecX& f_joint) {
  if (f_joint.size() != 6) {
    throw std::invalid_argument("joint_to_wrench: f_joint has " + std::to_string(f_joint.size()) +
                                " entries, expected 6");
  }
  return J1.transpose() * f_joint;
}

}  // namespace dentsim
