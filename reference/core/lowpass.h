// The discrete first-order low-pass every filter of the pipeline uses: over a step of length T,
//     y_k = y_k-1 + a (x_k - y_k-1),   a = 1 - exp(-2 pi f_c T)
// (the exact sampled response of 1 / (1 + s / (2 pi f_c)) to an input held over the step). The
// driver's velocity estimator (device/velocity_estimator.h) and the observer's matched input
// (reference/observer.h) must use the same a for the match to be exact; the grip detector's band
// filters use it too (reference/grip_detector.h).
#pragma once

#include <cmath>
#include <numbers>

namespace dentsim {

// a for cutoff f_c [Hz] and step T [s].
inline double lowpass_gain(double cutoff_hz, double T) {
  return 1.0 - std::exp(-2.0 * std::numbers::pi * cutoff_hz * T);
}

}  // namespace dentsim
