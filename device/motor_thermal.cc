#include "device/motor_thermal.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dentsim {

MotorThermal::MotorThermal(const MotorThermalParams& p)
    : active_(p.model == TorqueLimitModel::kThermal), p_(p) {
  for (int j = 0; j < 6; ++j) {
    rise_max_(j) = active_ ? p_.max_winding_c(j) - p_.ambient_c : 1.0;
    const double r = p_.r_winding_housing_k_per_w(j) + p_.r_housing_ambient_k_per_w(j);
    p_cont_(j) = active_ ? rise_max_(j) / r : 0.0;
  }
}

double MotorThermal::heat(int j, double tau) const noexcept {
  const double s = tau / p_.continuous_n_m(j);
  return p_cont_(j) * s * s;
}

void MotorThermal::exp_at(int j, double T, double e[4]) const noexcept {
  if (T == exp_T_(j)) {
    for (int k = 0; k < 4; ++k) e[k] = exp_e_(j, k);
    return;
  }
  // A = [-a, a; b, -(b + c)]: a = 1 / tau_w, b = R_ha / (tau_m R_wh), c = 1 / tau_m. Its
  // eigenvalues are real and distinct ((a + b + c)^2 - 4 a c = (a - c)^2 + b^2 + 2 b (a + c) > 0),
  // so e^{AT} = (e^{l1 T} (A - l2 I) - e^{l2 T} (A - l1 I)) / (l1 - l2).
  const double a = 1.0 / p_.tau_winding_s(j);
  const double c = 1.0 / p_.tau_motor_s(j);
  const double b = p_.r_housing_ambient_k_per_w(j) * c / p_.r_winding_housing_k_per_w(j);
  const double tr = -(a + b + c);
  const double disc = std::sqrt((a - c) * (a - c) + b * b + 2.0 * b * (a + c));
  const double l1 = 0.5 * (tr + disc), l2 = 0.5 * (tr - disc);
  const double e1 = std::exp(l1 * T), e2 = std::exp(l2 * T);
  const double d = l1 - l2;
  const double A[4] = {-a, a, b, -(b + c)};
  for (int k = 0; k < 4; ++k) {
    const double diag = (k == 0 || k == 3) ? 1.0 : 0.0;
    e[k] = (e1 * (A[k] - l2 * diag) - e2 * (A[k] - l1 * diag)) / d;
    exp_e_(j, k) = e[k];
  }
  exp_T_(j) = T;
}

double MotorThermal::allowed_torque(int j, double T) const noexcept {
  double e[4];
  exp_at(j, T, e);
  const double free = e[0] * tw_(j) + e[1] * th_(j);  // the winding at the tick's end, P = 0
  const double r1 = p_.r_winding_housing_k_per_w(j), r2 = p_.r_housing_ambient_k_per_w(j);
  const double gain = (1.0 - e[0]) * (r1 + r2) - e[1] * r2;  // its rise per watt held over T
  if (!(gain > 0.0)) return std::numeric_limits<double>::infinity();
  const double p_allowed = (rise_max_(j) - free) / gain;
  if (!(p_allowed > 0.0)) return 0.0;
  return p_.continuous_n_m(j) * std::sqrt(p_allowed / p_cont_(j));
}

bool MotorThermal::limit(VecX& tau, double T) const noexcept {
  if (!active_) return false;
  bool over = false;
  for (int j = 0; j < 6; ++j) {
    const double allowed = allowed_torque(j, T);
    const double a = std::abs(tau(j));
    if (a > allowed) over = true;
    if (p_.on_overheat == OnOverheat::kDerate) {
      const double lim = std::min(p_.peak_n_m(j), std::max(allowed, p_.continuous_n_m(j)));
      tau(j) = std::clamp(tau(j), -lim, lim);
    }
  }
  return over;
}

void MotorThermal::advance(const VecX& tau, double T) noexcept {
  if (!active_ || !(T > 0.0)) return;
  for (int j = 0; j < 6; ++j) {
    double e[4];
    exp_at(j, T, e);
    const double P = heat(j, tau(j));
    const double r1 = p_.r_winding_housing_k_per_w(j), r2 = p_.r_housing_ambient_k_per_w(j);
    const double sw = P * (r1 + r2), sh = P * r2;  // steady state of the held heat
    const double dw = tw_(j) - sw, dh = th_(j) - sh;
    tw_(j) = sw + e[0] * dw + e[1] * dh;
    th_(j) = sh + e[2] * dw + e[3] * dh;
  }
}

double MotorThermal::step_response(int j, double tau, double t) const noexcept {
  double e[4];
  exp_at(j, t, e);
  const double P = heat(j, tau);
  const double r1 = p_.r_winding_housing_k_per_w(j), r2 = p_.r_housing_ambient_k_per_w(j);
  return P * ((1.0 - e[0]) * (r1 + r2) - e[1] * r2);
}

}  // namespace dentsim
