#include "sim/quiet_measures.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace dentsim {

std::vector<double> centred_moving_average(std::span<const double> x, int h) {
  const long n = static_cast<long>(x.size());
  const long w = 2L * h + 1;
  std::vector<double> out;
  if (h < 0 || n < w) return out;
  out.reserve(static_cast<std::size_t>(n - w + 1));
  // Each window summed afresh: exact for the short windows used here (101 ticks), no drift.
  for (long j = 0; j + w <= n; ++j) {
    double s = 0.0;
    for (long i = j; i < j + w; ++i) s += x[static_cast<std::size_t>(i)];
    out.push_back(s / static_cast<double>(w));
  }
  return out;
}

double residual_rms(std::span<const double> x, int h) {
  const std::vector<double> avg = centred_moving_average(x, h);
  if (avg.empty()) return 0.0;
  double s = 0.0;
  for (std::size_t j = 0; j < avg.size(); ++j) {
    const double r = x[j + static_cast<std::size_t>(h)] - avg[j];
    s += r * r;
  }
  return std::sqrt(s / static_cast<double>(avg.size()));
}

std::optional<double> force_ripple(std::span<const double> f, int h) {
  const long n = static_cast<long>(f.size());
  if (h < 0 || n < 2L * h + 1) return std::nullopt;
  const double m =
      mean(f.subspan(static_cast<std::size_t>(h), static_cast<std::size_t>(n - 2L * h)));
  if (!(m > 0.0)) return std::nullopt;
  return residual_rms(f, h) / m;
}

double oscillation_amplitude(std::span<const double> x, std::span<const double> y,
                             std::span<const double> z, int h) {
  const double rx = residual_rms(x, h), ry = residual_rms(y, h), rz = residual_rms(z, h);
  return std::numbers::sqrt2 * std::sqrt(rx * rx + ry * ry + rz * rz);
}

double contact_fraction(std::span<const int> contacts) {
  if (contacts.empty()) return 0.0;
  long in = 0;
  for (int c : contacts) in += c > 0 ? 1 : 0;
  return static_cast<double>(in) / static_cast<double>(contacts.size());
}

int contact_losses(std::span<const int> contacts) {
  int losses = 0;
  for (std::size_t i = 0; i + 1 < contacts.size(); ++i) {
    if (contacts[i] > 0 && contacts[i + 1] <= 0) ++losses;
  }
  return losses;
}

std::optional<double> static_stiffness(std::span<const double> force,
                                       std::span<const double> penetration) {
  if (force.empty() || penetration.empty()) return std::nullopt;
  const double d = mean(penetration);
  if (!(d > 0.0)) return std::nullopt;
  return mean(force) / d;
}

double rms(std::span<const double> x) {
  if (x.empty()) return 0.0;
  double s = 0.0;
  for (double v : x) s += v * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

double mean(std::span<const double> x) {
  if (x.empty()) return 0.0;
  double s = 0.0;
  for (double v : x) s += v;
  return s / static_cast<double>(x.size());
}

long count_above(std::span<const double> x, double threshold) {
  long n = 0;
  for (double v : x) n += std::abs(v) > threshold ? 1 : 0;
  return n;
}

double rise(std::span<const double> x) { return x.size() < 2 ? 0.0 : x.back() - x.front(); }

void QuietSeries::reserve(std::size_t n) {
  t.reserve(n);
  contacts.reserve(n);
  contact_force_n.reserve(n);
  device_force_n.reserve(n);
  device_penetration_m.reserve(n);
  tip_x_m.reserve(n);
  tip_y_m.reserve(n);
  tip_z_m.reserve(n);
  energy_j.reserve(n);
  true_energy_j.reserve(n);
  observer_error_n.reserve(n);
}

bool phase_is_quiet(const QuietPhase& p, const QuietBounds& b) {
  if (!p.touched || p.ticks == 0) return false;
  if (!p.ripple_contact_force || !p.ripple_device_force) return false;
  return *p.ripple_contact_force <= b.ripple_max && *p.ripple_device_force <= b.ripple_max &&
         p.contact_fraction >= b.contact_fraction_min && p.contact_losses <= b.contact_losses_max;
}

int quiet_half_window(const QuietBounds& b, double tick_s) {
  return std::max(0, static_cast<int>(std::lround(0.5 * b.window_s / tick_s)));
}

namespace {

// Index range [i0, i1) of the samples with t in [t0, t1).
std::pair<std::size_t, std::size_t> index_range(const std::vector<double>& t, double t0,
                                                double t1) {
  const auto a = std::lower_bound(t.begin(), t.end(), t0);
  const auto b = std::lower_bound(a, t.end(), t1);
  return {static_cast<std::size_t>(a - t.begin()), static_cast<std::size_t>(b - t.begin())};
}

template <typename T>
std::span<const T> slice(const std::vector<T>& v, std::size_t i0, std::size_t i1) {
  return std::span<const T>(v).subspan(i0, i1 - i0);
}

}  // namespace

QuietReport quiet_report(const QuietSeries& s, const std::vector<QuietScriptKey>& script,
                         const QuietBounds& b, double tip_quantum_m) {
  QuietReport rep;
  rep.bounds = b;
  rep.tip_quantum_m = tip_quantum_m;
  const int h = quiet_half_window(b, s.tick_s);
  const double t_last = s.t.empty() ? 0.0 : s.t.back() + s.tick_s;

  // Steady contact phases: runs of script segments [key i, key i+1) with the same label and the
  // same non-zero feed-forward force at both keys.
  for (std::size_t i = 0; i + 1 < script.size();) {
    const QuietScriptKey& k0 = script[i];
    std::size_t j = i;
    bool moves = false;
    while (j + 1 < script.size() && script[j + 1].phase == k0.phase &&
           script[j + 1].force == k0.force && k0.force.norm() > 0.0) {
      moves = moves || script[j + 1].offset != script[j].offset;
      ++j;
    }
    if (j == i) {
      ++i;
      continue;
    }
    QuietPhase p;
    p.phase = k0.phase;
    p.kind = moves ? "slide" : "press";
    p.t_begin_s = k0.t;
    p.t_end_s = std::min(script[j].t, t_last);
    i = j;
    const auto [a0, a1] = index_range(s.t, p.t_begin_s, p.t_end_s);
    std::size_t first = a1;
    for (std::size_t k = a0; k < a1; ++k) {
      if (s.contacts[k] > 0) {
        first = k;
        break;
      }
    }
    p.touched = first < a1;
    p.steady_from_s = p.touched ? s.t[first] + b.settle_s : p.t_end_s;
    // Pushing into the air all along (an approach) is no contact phase; too short a stretch after
    // the settling is not reported either.
    if (!p.touched || p.t_end_s - p.steady_from_s < b.min_steady_s) continue;
    const auto [i0, i1] = index_range(s.t, p.steady_from_s, p.t_end_s);
    p.ticks = static_cast<long>(i1 - i0);
    if (p.ticks > 0) {
      const auto fc = slice(s.contact_force_n, i0, i1);
      const auto fd = slice(s.device_force_n, i0, i1);
      const auto dp = slice(s.device_penetration_m, i0, i1);
      p.ripple_contact_force = force_ripple(fc, h);
      p.ripple_device_force = force_ripple(fd, h);
      p.contact_fraction = contact_fraction(slice(s.contacts, i0, i1));
      p.contact_losses = contact_losses(slice(s.contacts, i0, i1));
      p.oscillation_amplitude_m = oscillation_amplitude(
          slice(s.tip_x_m, i0, i1), slice(s.tip_y_m, i0, i1), slice(s.tip_z_m, i0, i1), h);
      p.oscillation_amplitude_quanta =
          tip_quantum_m > 0.0 ? p.oscillation_amplitude_m / tip_quantum_m : 0.0;
      p.mean_contact_force_n = mean(fc);
      p.mean_device_force_n = mean(fd);
      p.mean_penetration_m = mean(dp);
      p.static_stiffness_n_per_m = static_stiffness(fd, dp);
      p.motor_energy_j = rise(slice(s.energy_j, i0, i1));
      if (s.observer_error_n.size() == s.t.size()) {
        p.observer_rms_error_n = rms(slice(s.observer_error_n, i0, i1));
      }
    }
    p.quiet = phase_is_quiet(p, b);
    rep.phases.push_back(std::move(p));
  }

  // Free space: ticks with no contact within the window (h ticks either side); the hand
  // "moving" while its reference moves between two keys, "still" from still_settle_s after it
  // stopped (equal offsets at both keys, or past the last key).
  std::vector<long> in_contact(s.t.size() + 1, 0);  // prefix count of contact ticks
  for (std::size_t k = 0; k < s.t.size(); ++k)
    in_contact[k + 1] = in_contact[k] + (s.contacts[k] > 0);
  std::vector<double> moving_f, still_f, moving_obs, still_obs;
  const bool observer_measured = !s.t.empty() && s.observer_error_n.size() == s.t.size();
  const bool true_energy_measured = !s.t.empty() && s.true_energy_j.size() == s.t.size();
  QuietFreeSpace& fs = rep.free_space;
  double still_since = -1.0;  // when the reference last stopped (-1: moving)
  std::size_t still_run_begin = 0;
  bool in_still_run = false;
  auto close_still_run = [&](std::size_t end) {
    if (in_still_run && end > still_run_begin + 1) {
      fs.still_motor_energy_j += rise(slice(s.energy_j, still_run_begin, end));
      if (true_energy_measured) {
        fs.still_true_motor_energy_j =
            fs.still_true_motor_energy_j.value_or(0.0) +
            rise(slice(s.true_energy_j, still_run_begin, end));
      }
    }
    in_still_run = false;
  };
  std::size_t seg = 0;
  const std::size_t n = s.t.size();
  for (std::size_t k = 0; k < n; ++k) {
    const double t = s.t[k];
    while (seg + 1 < script.size() && script[seg + 1].t <= t) ++seg;
    bool moving = false;
    if (!script.empty() && t >= script.front().t && seg + 1 < script.size()) {
      moving = script[seg].offset != script[seg + 1].offset;
    }
    if (moving) {
      still_since = -1.0;
    } else if (still_since < 0.0) {
      still_since = t;
    }
    const bool still = !moving && t >= still_since + b.still_settle_s;
    const std::size_t lo = k >= static_cast<std::size_t>(h) ? k - h : 0;
    const std::size_t hi = std::min(n, k + h + 1);
    const bool free = in_contact[hi] == in_contact[lo];
    if (moving && free) {
      moving_f.push_back(s.device_force_n[k]);
      if (observer_measured) moving_obs.push_back(s.observer_error_n[k]);
    }
    if (still && free) {
      still_f.push_back(s.device_force_n[k]);
      if (observer_measured) still_obs.push_back(s.observer_error_n[k]);
      if (!in_still_run) {
        in_still_run = true;
        still_run_begin = k;
      }
    } else {
      close_still_run(k);
    }
  }
  close_still_run(n);
  fs.moving_ticks = static_cast<long>(moving_f.size());
  fs.still_ticks = static_cast<long>(still_f.size());
  fs.moving_force_rms_n = rms(moving_f);
  fs.still_force_rms_n = rms(still_f);
  if (!moving_obs.empty()) fs.moving_observer_rms_error_n = rms(moving_obs);
  if (!still_obs.empty()) fs.still_observer_rms_error_n = rms(still_obs);
  fs.still_pulses = count_above(still_f, b.pulse_threshold_n);
  fs.still_s = static_cast<double>(still_f.size()) * s.tick_s;
  fs.still_pulse_rate_per_s =
      still_f.empty() ? 0.0 : fs.still_pulses / (static_cast<double>(still_f.size()) * s.tick_s);

  bool all = true;
  for (const QuietPhase& p : rep.phases) all = all && p.quiet;
  if (!rep.phases.empty()) rep.quiet = all;
  return rep;
}

}  // namespace dentsim
