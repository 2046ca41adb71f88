// The supervisor of the virtual side (issue #32): invariants the loop owner (device/closed_loop.h)
// checks on every tick's result before its torque reaches the device, so that a diverged
// simulation never drives the device. The safety chain (device/safety_chain.h) guards the
// device's side (torques, joint velocities, workspace); this guards the proxy's:
//
//   virtual_non_finite           any of the proxy's pose, twist, the evaluated velocity V_hat,
//                                the contact / coupling wrenches, the device wrench T1 or the
//                                joint command not finite
//   contact_force_beyond_bound   |f| of the contact (+ friction) force on the proxy > F_bound
//   coupling_force_beyond_bound  |f| of the coupling force on the proxy or on the device
//                                > F_bound
//                                F_bound = force_bound_multiple * peak_force (default 4 x 8.5 N
//                                = 34 N: a stable rendering feeds back what the hand pushes, a
//                                few newtons; the device saturates at its peak force)
//   proxy_too_deep               the deepest contact of the proxy deeper than the tool's radius
//                                plus the compression the force bound needs on the softest
//                                member of the set (F_bound / K): beyond it the tool's centre is
//                                inside the tooth further than any admissible force explains (a
//                                tunnelled or diverged proxy; the surface-proxy contact reports
//                                the tool's distance behind the rendered surface, F / K)
//   proxy_too_far                |x_proxy - x_device| > max_separation (default the Phantom's
//                                smallest workspace extent, 191 mm: no coupling can be stretched
//                                that far by a hand)
//   virtual_energy_growth        the contact gives back more energy than it took:
//                                W_c(k) = sum_j T_j V_hat_j^T F_contact,j > energy_tolerance
//   tick_too_late                the tick length the pipeline integrates over (the loop's
//                                measured T_k) > max_tick_s (default: the larger of 50 ms and 5
//                                nominal periods). A late tick is a fact of life on a real machine
//                                (a preempted thread, a scheduler that skipped ticks): it is
//                                ridden through and counted (late_ticks: T_k > 1.5 nominal
//                                periods; max_tick_s), since PMI integrates any T_k; past the
//                                bound the hand has moved unobserved for too long (tens of ms)
//                                and the observer's L T_k < 1 fails at the built-ins' gains.
//
// The energy observer (Hannaford & Ryu's time-domain passivity observer, on the virtual side):
// the contact is a passive element (a potential U >= 0 plus damping and friction), so the work it
// does on the proxy, W_c = sum T V_hat^T F_c, never exceeds U(0) - U(k) <= U(0) = 0 (the run
// starts out of contact; drilling only removes stored energy). It is computed from the pipeline's
// own state at the velocity the forces were evaluated at, so encoder quantisation (which enters
// only through the device's twist, on the coupling's side of the port) does not enter it; what
// remains is the midpoint rule's error on a contact set that changes within a tick (members that
// appear or leave mid-tick, the SDF's normal turning), bounded by the potential one tick's
// motion can store: energy_tolerance (default 50 mJ, four times the energy a contact holds at
// the device's peak force on the softest tooth the scene format allows, 1/2 F^2/K = 12 mJ for
// 8.5 N on 3000 N/m) is far above it, and far below what a diverging contact returns within a
// few ticks. The hand feeds energy only through the coupling, never through the contact, so a
// hand pushing hard does not count.
//
// Every fault latches in the loop owner, which commands zero torque from that tick on. check()
// never allocates and never throws.
#pragma once

#include <cstdint>
#include <string>

#include "reference/core/params.h"
#include "reference/core/pipeline.h"

namespace dentsim {

enum class SupervisorFault : std::uint8_t {
  kNone = 0,
  kNonFinite,
  kContactForce,
  kCouplingForce,
  kProxyTooDeep,
  kProxyTooFar,
  kEnergyGrowth,
  kLateTick,
};
// "none", "virtual_non_finite", "contact_force_beyond_bound", "coupling_force_beyond_bound",
// "proxy_too_deep", "proxy_too_far", "virtual_energy_growth", "tick_too_late".
const char* supervisor_fault_name(SupervisorFault f);

struct SupervisorLimits {
  double peak_force_n = 8.5;          // the device's peak force [N] (Phantom Premium 1.5)
  double force_bound_multiple = 4.0;  // F_bound = multiple * peak force
  double tool_radius_m = 0.5e-3;      // proxy_too_deep beyond it [m] (<= 0: no depth check)
  double max_separation_m = 0.191;    // proxy_too_far beyond it [m] (<= 0: no check)
  double energy_tolerance_j = 0.05;   // virtual_energy_growth beyond it [J] (<= 0: no check)
  double nominal_period_s = 1e-3;     // the device's nominal tick [s]
  // tick_too_late beyond it [s]; 0: the default max(0.05 s, 5 nominal periods); < 0: no check.
  double max_tick_s = 0.0;
  double tick_bound_s() const {
    if (max_tick_s != 0.0) return max_tick_s;
    return nominal_period_s * 5.0 > 0.05 ? nominal_period_s * 5.0 : 0.05;
  }
  double force_bound_n() const { return force_bound_multiple * peak_force_n; }
};

// Throws InputError naming the field unless every limit is finite, the peak force and the
// multiple positive.
void validate_supervisor_limits(const SupervisorLimits& limits);

class VirtualSupervisor {
 public:
  explicit VirtualSupervisor(const SupervisorLimits& limits);  // validates
  void start() noexcept {
    contact_work_ = 0.0;
    fault_ = SupervisorFault::kNone;
    value_ = 0.0;
    late_ticks_ = 0;
    max_tick_s_ = 0.0;
  }
  // One tick's result `r` (its tick of length T) and the proxy after it. Returns the fault it
  // finds (kNone: all invariants hold); the first fault is kept (fault(), value()).
  SupervisorFault check(const TickResult& r, const ProxyState& proxy, double T) noexcept;
  SupervisorFault fault() const { return fault_; }
  // The offending figure of the fault (force [N], depth or distance [m], energy [J]; 0 for
  // non-finite).
  double value() const { return value_; }
  double contact_work_j() const { return contact_work_; }  // W_c so far [J]
  const SupervisorLimits& limits() const { return limits_; }
  // The latched fault's figure against its bound, e.g. "|f| = 230 N > 34 N" (empty while none;
  // allocates: not for the tick).
  std::string describe() const;
  // Ridden-through lateness: ticks longer than 1.5 nominal periods, and the longest tick [s].
  long late_ticks() const { return late_ticks_; }
  double max_tick_s() const { return max_tick_s_; }

 private:
  SupervisorLimits limits_;
  double contact_work_ = 0.0;
  SupervisorFault fault_ = SupervisorFault::kNone;
  double value_ = 0.0;
  long late_ticks_ = 0;
  double max_tick_s_ = 0.0;
  double depth_bound(const TickResult& r) const noexcept;
};

}  // namespace dentsim
