// A thermal torque limit for the simulated device's motors (issue #29, the tap target; model-file
// key "torque_limit": {"model": "thermal", ...}, reference/phantom/phantom_params.h). The real
// Phantom's motors take their peak torque for a short time and their continuous torque for ever;
// the hardware reports the motors' temperature (HD_MOTOR_TEMPERATURE) and stops forces with
// HD_WARM_MOTORS when they overheat. This is that, per joint j, as a two-node thermal network of a
// DC motor (the maxon catalogue's thermal data: winding and housing; docs/simulated_device.md):
//
//   C_w dTw/dt = P - (Tw - Th) / R_wh,        C_h dTh/dt = (Tw - Th) / R_wh - Th / R_ha,
//
// Tw, Th the winding's and the housing's rise above ambient [K], C_w = tau_w / R_wh and
// C_h = tau_m / R_ha [J/K] (maxon: "calculated from the product of thermal capacity and given heat
// resistances"), the Joule heat P = P_cont (tau / tau_cont)^2 with P_cont = Tmax / (R_wh + R_ha)
// (tau_cont is the torque whose steady-state winding sits at its limit: the motor's continuous
// rating; the winding's resistance is taken at that temperature, constant). A torque held over a
// tick of length T (zero-order hold) is integrated exactly:
//
//   x(T) = x_ss + e^{AT} (x0 - x_ss),   x = (Tw, Th),   x_ss = P (R_wh + R_ha, R_ha).
//
// The limit of the tick about to run: |tau| <= peak, and |tau| <= tau_allowed, the torque that
// takes the winding exactly to Tmax at the end of the tick (Tw(T) is linear in P). With
// on_overheat "derate" the torque is clipped to max(tau_allowed, tau_cont) (the continuous rating
// never heats a winding at or below Tmax past it: tau_allowed >= tau_cont there); with "fault" a
// command beyond tau_allowed latches kFaultMotorTemperature ("motor_temperature", the safety
// chain's name for a warm motor) and the device applies zero torque until clear_faults().
// Nothing here allocates or throws after construction.
#pragma once

#include <limits>

#include "reference/core/types.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

class MotorThermal {
 public:
  MotorThermal() = default;
  // Per-joint model of `p` (kThermal), all joints at ambient.
  explicit MotorThermal(const MotorThermalParams& p);

  bool active() const { return active_; }
  const MotorThermalParams& params() const { return p_; }

  // Clips `tau` (in place, per joint) to the limit of a tick of length T [s] from the present
  // state; returns true when some |tau_j| exceeded tau_allowed,j (on_overheat "fault": the caller
  // latches the fault and applies zero; "derate": tau is already clipped).
  bool limit(VecX& tau, double T) const noexcept;
  // Advances the state over a tick of length T [s] with `tau` held (the torque applied).
  void advance(const VecX& tau, double T) noexcept;

  // The torque of joint j that takes its winding to Tmax at the end of a tick of length T [s],
  // from the present state (+inf while the winding cannot reach Tmax; 0 if it is already past).
  double allowed_torque(int j, double T) const noexcept;
  // Winding and housing rise above ambient [K].
  double winding_rise(int j) const { return tw_(j); }
  double housing_rise(int j) const { return th_(j); }
  // Winding temperature [deg C], and normalised 0 (ambient) .. 1 (Tmax): HD_MOTOR_TEMPERATURE's
  // scale.
  double winding_temperature_c(int j) const { return p_.ambient_c + tw_(j); }
  double normalised_temperature(int j) const { return tw_(j) / rise_max_(j); }
  // The rise of the winding held at constant torque tau from ambient for time t (exact solution of
  // the network: the closed form the tests check the stepping against).
  double step_response(int j, double tau, double t) const noexcept;

 private:
  // e^{A T} of joint j's network (2x2, row-major a11 a12 a21 a22). A device tick asks it twice
  // with the same T (limit, then advance): the last T's matrix is kept per joint, so the two
  // exponentials are taken once a tick (the same doubles either way).
  void exp_at(int j, double T, double e[4]) const noexcept;
  double heat(int j, double tau) const noexcept;  // P [W]

  bool active_ = false;
  MotorThermalParams p_;
  Vec6 rise_max_ = Vec6::Ones();  // Tmax - T_amb [K]
  Vec6 p_cont_ = Vec6::Zero();    // [W]
  Vec6 tw_ = Vec6::Zero(), th_ = Vec6::Zero();
  // exp_at's last T and its e^{AT}, per joint (NaN: none yet).
  mutable Vec6 exp_T_ = Vec6::Constant(std::numeric_limits<double>::quiet_NaN());
  mutable Eigen::Matrix<double, 6, 4, Eigen::RowMajor> exp_e_ = decltype(exp_e_)::Zero();
};

}  // namespace dentsim
