#include "device/velocity_estimator.h"

#include <cmath>
#include <string>

#include "reference/core/io.h"
#include "reference/core/lowpass.h"

namespace dentsim {

VelocityEstimator::VelocityEstimator(int n, VelocityEstimatorParams params) : params_(params) {
  if (n < 1)
    throw InputError("velocity estimator: joint count " + std::to_string(n) + ", expected >= 1");
  if (params_.filter == VelocityFilter::kFirstOrderLowPass &&
      !(std::isfinite(params_.cutoff_hz) && params_.cutoff_hz > 0.0)) {
    throw InputError("velocity estimator: cutoff_hz = " + std::to_string(params_.cutoff_hz) +
                     ", expected a positive finite frequency [Hz]");
  }
  q_prev_ = VecX::Zero(n);
  qd_ = VecX::Zero(n);
}

void VelocityEstimator::reset(const VecX& q, double t, const VecX& qd0) {
  q_prev_ = q;
  qd_ = qd0;
  t_prev_ = t;
}

const VecX& VelocityEstimator::update(const VecX& q, double t) {
  const double T = t - t_prev_;
  if (!(T > 0.0)) return qd_;  // time fault: keep the last estimate
  if (params_.filter == VelocityFilter::kBackwardDifference) {
    qd_ = (q - q_prev_) / T;
  } else {
    const double a = lowpass_gain(params_.cutoff_hz, T);
    qd_ += a * ((q - q_prev_) / T - qd_);
  }
  q_prev_ = q;
  t_prev_ = t;
  return qd_;
}

}  // namespace dentsim
