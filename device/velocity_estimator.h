// Joint-velocity estimation from quantised encoder angles, as a haptic driver computes it
// (OpenHaptics reports no joint velocity: docs/device_facts.md §5).
//
// Backward difference over the measured tick length T_k [s] (T_k may vary tick to tick):
//     qd_raw,k = (q_k - q_k-1) / T_k                                                  [rad/s]
// With encoder quantum Delta, |(q_k - q_k-1) - (q_true,k - q_true,k-1)| < Delta, so the raw
// estimate differs from the true mean velocity over the tick by less than Delta / T_k.
// Optional first-order low-pass (cut-off f_c [Hz]), discretised exactly for an input held over
// the tick (zero-order hold), so it stays right when T_k varies:
//     a_k = 1 - exp(-2 pi f_c T_k),   qd_k = qd_k-1 + a_k (qd_raw,k - qd_k-1)
// It has unit DC gain (no steady-state error at constant velocity), a lag of about
// 1 / (2 pi f_c) at low frequency, and, being a convex combination of raw estimates, keeps their
// error bound Delta / min T once the start-up transient has decayed.
#pragma once

#include "reference/core/types.h"

namespace dentsim {

enum class VelocityFilter {
  kBackwardDifference,  // qd_raw only
  kFirstOrderLowPass,   // low-passed backward difference
};

struct VelocityEstimatorParams {
  VelocityFilter filter = VelocityFilter::kFirstOrderLowPass;
  double cutoff_hz = 200.0;  // f_c [Hz] of the low-pass
};

class VelocityEstimator {
 public:
  // n joints. Throws InputError if n < 1 or the cut-off is not positive and finite.
  VelocityEstimator(int n, VelocityEstimatorParams params);

  // Starts from angles q at time t with velocity qd0 (typically zero).
  void reset(const VecX& q, double t, const VecX& qd0);
  // New angles q at time t > previous t. Returns the estimate (a reference to internal storage,
  // valid until the next call). A non-positive T_k leaves the estimate unchanged (the device
  // reports the time fault). No allocation.
  const VecX& update(const VecX& q, double t);

  const VecX& estimate() const { return qd_; }
  const VelocityEstimatorParams& params() const { return params_; }

 private:
  VelocityEstimatorParams params_;
  VecX q_prev_;
  VecX qd_;
  double t_prev_ = 0.0;
};

}  // namespace dentsim
