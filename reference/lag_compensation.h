// Loop-lag compensation of the device velocity (issue #29 item 3; docs/derivations/
// quiet_stiffness.md "Loop-lag compensation").
//
// Above ~6000 N/m the contact mode of pmi-pd (the desired tool mass M_d on the tooth's K) loses
// the damping of the hand, the tooth and D_d to the lags of the loop: the coupling damper and the
// decomposition's D_d act on a velocity that is older than the one the command they produce will
// meet. Those lags are known from the clock and the driver, not fitted:
//
//   zero-order hold   the command is held over the coming tick T_next: on average it acts at
//                     the tick's midpoint, T_next / 2 after the sample;
//   backward diff.    (q_k - q_k-1) / T_last is the velocity at the middle of the tick that
//                     ended: T_last / 2 behind the sample (on a motion of constant acceleration);
//   low-pass          y_k = y_k-1 + a (x_k - y_k-1), a = 1 - exp(-2 pi f_c T_last), lags a ramp by
//                     exactly T_last (1 - a) / a in steady state (x_k - y_k = s (1 - a) / a for a
//                     ramp of slope s per tick; ~ 1 / (2 pi f_c) for f_c T << 1).
//
// The compensated velocity advances the driver's estimate over that lag with the device model's
// acceleration, the one the encoder Kalman filter predicts with (reference/encoder_kalman.h):
//
//   qd_loop = qd + lag a,   a = M^-1 (tau_prev + f_hat - g - tau_f)
//
// (the torque applied over the tick that ended, the observer's estimate of the hand, the
// hypothesis in force of the grip detector). On a motion of constant acceleration qd_loop is
// exactly the velocity at the midpoint of the coming tick. The coupling (both sides) and the
// decomposition's D_d use V1 = J_t qd_loop; the observer and the hand's terms keep the measured
// velocity (the observer's input is matched to the driver's estimate, reference/observer.h).
// Nothing is added that a user feels in free space: the compensation only moves the velocity the
// existing dampers see to the time their force acts.
#pragma once

#include "reference/core/params.h"  // ObserverInput

namespace dentsim {

// The lag [s] of the driver's velocity estimate behind the true velocity at the sample, on a
// motion of constant acceleration: T_last / 2 for a backward difference, plus T_last (1 - a) / a
// for its first-order low-pass at f_c = estimate.lowpass_hz (a = 1 - exp(-2 pi f_c T_last)).
// An estimate that is neither (a measured velocity, the encoder Kalman filter's) has no lag.
double velocity_estimate_lag(const ObserverInput& estimate, double T_last);

// The whole loop's lag [s]: the estimate's lag plus the zero-order hold's T_next / 2.
double loop_velocity_lag(const ObserverInput& estimate, double T_last, double T_next);

}  // namespace dentsim
