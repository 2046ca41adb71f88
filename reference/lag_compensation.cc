#include "reference/lag_compensation.h"

#include "reference/core/lowpass.h"

namespace dentsim {

double velocity_estimate_lag(const ObserverInput& estimate, double T_last) {
  double lag = 0.0;
  if (estimate.match_backward_difference) lag += 0.5 * T_last;
  if (estimate.lowpass_hz > 0.0) {
    const double a = lowpass_gain(estimate.lowpass_hz, T_last);
    if (a > 0.0) lag += T_last * (1.0 - a) / a;
  }
  return lag;
}

double loop_velocity_lag(const ObserverInput& estimate, double T_last, double T_next) {
  return velocity_estimate_lag(estimate, T_last) + 0.5 * T_next;
}

}  // namespace dentsim
