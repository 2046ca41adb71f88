// Quiet measures (issue #29, item 1): is a rendered stiffness felt as a steady force, or as a
// buzz? Pure functions over time series sampled at a fixed tick (no device, no pipeline), so that
// `dentsim run` (sim/run_report.h: the report's `quiet` block) and `dentsim zwidth`
// (validation/zwidth.h: a run's `quiet` verdict) measure the same thing the same way.
//
// The measures of one steady stretch of signal:
// - ripple of a force f: RMS of f minus its centred moving average over 2h+1 samples (0.1 s),
//   over the mean of f; both taken where the whole window fits (samples h .. n-1-h). A constant
//   force has ripple 0; f = m + A sin(2 pi t / P) with the window and the stretch whole periods
//   has ripple A / (sqrt 2 m);
// - contact fraction: the fraction of ticks with at least one contact;
// - contact losses: the number of ticks in contact followed by a tick without (a stretch that
//   ends out of contact counts its last loss; one that starts out of contact does not count it);
// - oscillation amplitude of a position x (3-D): sqrt 2 times the RMS of |x minus its centred
//   moving average| (the amplitude of a sine), in encoder quanta when divided by the tip's quantum;
// - static stiffness: mean force over mean penetration;
// - force RMS, count of samples above a threshold (pulses), rise of an energy (last - first).
//
// quiet_report() cuts a run into the phases of its scripted hand and applies these measures:
// steady contact phases (the hand pushes with a constant, non-zero feed-forward force between
// two keys of the same phase label: a "press" when the reference stands still, a "slide" when it
// moves), measured from the first contact + settle_s to the phase's end (a phase that never
// touches is no contact phase: the hand pushed into the air); and free space (ticks with no
// contact within half a window either side: "moving" while the hand's reference moves between
// two keys, "still" once it has stood for still_settle_s).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "reference/core/types.h"

namespace dentsim {

// The centred moving average of x over 2h+1 samples, where the whole window fits: element j is
// the mean of x[j .. j+2h] (n - 2h elements; empty if n < 2h + 1). h >= 0.
std::vector<double> centred_moving_average(std::span<const double> x, int h);

// RMS of x[i] - (its centred moving average) over i in [h, n-1-h]; 0 if n < 2h + 1.
double residual_rms(std::span<const double> x, int h);

// residual_rms(f, h) over the mean of f[h .. n-1-h]; empty if n < 2h + 1 or that mean <= 0.
std::optional<double> force_ripple(std::span<const double> f, int h);

// sqrt 2 times the RMS over i in [h, n-1-h] of |p_i - (the centred moving average of p)|, p
// given by its three coordinates (equal lengths); 0 if n < 2h + 1.
double oscillation_amplitude(std::span<const double> x, std::span<const double> y,
                             std::span<const double> z, int h);

// Fraction of entries > 0 (0 for an empty series).
double contact_fraction(std::span<const int> contacts);

// Number of i with contacts[i] > 0 and contacts[i+1] == 0.
int contact_losses(std::span<const int> contacts);

// mean(force) / mean(penetration); empty if the series is empty or mean(penetration) <= 0.
std::optional<double> static_stiffness(std::span<const double> force,
                                       std::span<const double> penetration);

double rms(std::span<const double> x);   // 0 for an empty series
double mean(std::span<const double> x);  // 0 for an empty series
// Number of entries with |x| > threshold.
long count_above(std::span<const double> x, double threshold);
// x.back() - x.front() (0 for fewer than two entries).
double rise(std::span<const double> x);

// The bounds a steady contact phase is judged quiet against, and how the run is cut.
struct QuietBounds {
  double ripple_max = 0.05;           // force ripple, contact force and force on the device
  double contact_fraction_min = 1.0;  // contact on every tick
  int contact_losses_max = 0;         // no contact loss
  double window_s = 0.1;              // the moving average's window (2h+1 ticks)
  double settle_s = 0.3;              // a contact phase is measured from first contact + this
  double min_steady_s = 0.2;          // shorter steady stretches are not reported
  double pulse_threshold_n = 0.1;     // free space, hand still: |F| above this is a pulse
  double still_settle_s = 0.5;        // "still" from this long after the reference stops
};

// One tick of the run, as the measures need it.
struct QuietSeries {
  double tick_s = 1e-3;
  std::vector<double> t;                     // [s]
  std::vector<int> contacts;                 // contact count
  std::vector<double> contact_force_n;       // |f| on the proxy
  std::vector<double> device_force_n;        // |f| fed back to the device (what the hand feels)
  std::vector<double> device_penetration_m;  // the device tip's own penetration
  std::vector<double> tip_x_m, tip_y_m, tip_z_m;  // device tip position (world)
  std::vector<double> energy_j;                   // E_v, the energy the motors put in so far
  // The motors' true work so far: the torque applied over each tick times the device's true joint
  // motion (E_v without the encoders' error). Empty without ground truth (a real device).
  std::vector<double> true_energy_j;
  // |f_hat - f_hand|: the human-force observer's error against the hand's true force (issue #29's
  // observer target). Empty when the device has no ground truth (a real device): not measured.
  std::vector<double> observer_error_n;
  void reserve(std::size_t n);
};

// One key of the scripted hand: reference offset and feed-forward force, from t on.
struct QuietScriptKey {
  double t = 0.0;
  Vec3 offset = Vec3::Zero();
  Vec3 force = Vec3::Zero();
  std::string phase;
};

struct QuietPhase {
  std::string phase;                      // the script's label
  std::string kind;                       // "press" or "slide"
  double t_begin_s = 0.0, t_end_s = 0.0;  // the script's phase
  double steady_from_s = 0.0;             // first contact + settle_s (= t_end_s: never touched)
  long ticks = 0;                         // steady ticks measured
  bool touched = false;
  std::optional<double> ripple_contact_force, ripple_device_force;
  double contact_fraction = 0.0;
  int contact_losses = 0;
  double oscillation_amplitude_m = 0.0;
  double oscillation_amplitude_quanta = 0.0;
  double mean_contact_force_n = 0.0, mean_device_force_n = 0.0, mean_penetration_m = 0.0;
  std::optional<double> static_stiffness_n_per_m;  // mean device force / mean device penetration
  double motor_energy_j = 0.0;                     // rise of E_v over the steady ticks
  std::optional<double> observer_rms_error_n;      // RMS of observer_error_n over the steady ticks
  bool quiet = false;
};

struct QuietFreeSpace {
  long moving_ticks = 0, still_ticks = 0;
  double moving_force_rms_n = 0.0;  // |force on the device| RMS, reference moving, no contact
  double still_force_rms_n = 0.0;   // the same, hand still
  long still_pulses = 0;            // still ticks with |force| > pulse_threshold_n
  double still_pulse_rate_per_s = 0.0;
  double still_motor_energy_j = 0.0;  // sum of the rises of E_v over still stretches
  // The same for the motors' true work (QuietSeries::true_energy_j), when measured.
  std::optional<double> still_true_motor_energy_j;
  double still_s = 0.0;               // still_ticks * tick
  // RMS of observer_error_n over the moving / still free-space ticks (when measured).
  std::optional<double> moving_observer_rms_error_n, still_observer_rms_error_n;
};

struct QuietReport {
  QuietBounds bounds;
  double tip_quantum_m = 0.0;
  std::vector<QuietPhase> phases;
  QuietFreeSpace free_space;
  // Every reported contact phase quiet; empty when there is none.
  std::optional<bool> quiet;
};

// The verdict of one phase's measures against the bounds.
bool phase_is_quiet(const QuietPhase& p, const QuietBounds& b);

// The window's half-width in ticks: round(window_s / (2 tick_s)).
int quiet_half_window(const QuietBounds& b, double tick_s);

// Cuts the run into the script's phases (keys in time order) and measures them (see the top).
QuietReport quiet_report(const QuietSeries& s, const std::vector<QuietScriptKey>& script,
                         const QuietBounds& b, double tip_quantum_m);

}  // namespace dentsim
