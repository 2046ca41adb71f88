// Shape control that stays passive under actuator saturation (issue #29 item 3; docs/derivations/
// quiet_stiffness.md section 6).
//
// The problem. The tick solves the proxy (solve) as if the device received its whole command
// T1 = T1_vc + T1_pd, then scales the joint torque uniformly to the limits (command). When a press
// asks more than the motors give, the decomposition's premise breaks: the locked system's drive X
// of (4.7) is never realised by the device, the proxy keeps its share of it, and the pair settles
// where the proxy's share of X balances the coupling, with a contact force on the proxy many times
// the hand's (section 6: 13 N on the proxy, 4.5 mm deep, for a 1.2 N hand at K 3000 N/m).
//
// The design: the virtual side sees only what the device can deliver. Once a command saturates,
// until the device is back within its limits with the cap below not binding:
//
//   1. the feed-forward (4.7) on both sides is scaled by sigma in [0, 1]:
//        T1_pd -> sigma T1_pd,  T2_pd -> sigma T2_pd,
//      sigma the largest value for which the command of the tick that ended,
//        tau(sigma) = J_t^T (T1_vc + sigma T1_pd) + g,
//      stays within (1 - kSaturationHeadroom) of every joint's limit (each joint bounds sigma
//      linearly), lowered at once, raised by at most T / kShapeSigmaRecoveryS per tick. sigma = 0
//      is the PMI coupling (pmi) alone; sigma = 1 is pmi-pd untouched.
//   2. the coupling's linear spring (both sides, (4.3) and (4.5)) is capped at the force F_cap the
//      device can deliver along it at this pose, the largest F with
//        |F (J_t^T [u; 0])_i + g_i| <= (1 - kSaturationHeadroom) L_i   for every joint i,
//      u the unit vector from the device to the proxy (0 when the gravity torque alone exceeds a
//      limit). The capped spring is the gradient of a convex potential (quadratic up to F_cap / k,
//      linear beyond: a Huber function of the stretch): conservative, so it stores at most what
//      the device's motion put in and gives back no more; the proxy is never pulled by more than
//      the device can push back, so a contact holds it at depth <= F_cap / K_tooth while the hand
//      takes the device deeper.
//
// Why it is passive. sigma only scales the feed-forward towards the plain PMI coupling, which is
// passive on its own (docs/derivations/pmi_and_coupling.md); lowering sigma moves the locked
// system's rendered inertia from M_d towards M_L <= M_d (sim/simulator.cc puts M_d at least at
// M_L), which can only lower its kinetic storage at a given velocity; raising it back is rate
// limited and allowed only while the cap does not bind, so the energy it can add is bounded by
// 1/2 v_L^T (M_d - M_L) v_L at the velocities of those ticks (~0 in a press). The cap is a
// conservative spring (above); it engages and releases where the capped and the plain spring agree
// (release only once the cap does not bind). Tested as an energy balance at the hand port
// (tests/reference/saturation_passive_test.cc).
//
// Why it changes nothing unsaturated: the state engages only on a command that saturated; until
// then no term is touched (bitwise). A scene's switch (method.saturation_passive) is on by default;
// the built-in scenes at their quiet gains never saturate, so their runs are the same on and off.
// PipelineConfig's own default stays off (the library's callers choose).
//
// Allocation-free and throw-free (6x6 fixed-size algebra only).
#pragma once

#include "reference/core/affine_wrench.h"
#include "reference/core/types.h"

namespace dentsim {

// Fraction of each joint's torque limit the engaged shape control keeps free, so that its command
// sits inside the limits rather than on them.
inline constexpr double kSaturationHeadroom = 0.02;
// Time over which sigma may return from 0 to 1 [s]: long against the coupling mode (~25 Hz), so
// the feed-forward comes back without a step.
inline constexpr double kShapeSigmaRecoveryS = 0.1;

// The largest force F >= 0 the device delivers at its tip along the unit vector u (no moment)
// within |tau_i| <= limit_i (1 - headroom), tau = F J_t^T [u; 0] + tau_gravity.
double deliverable_force(const Mat6& J_t, const Vec6& torque_limit, const Vec6& tau_gravity,
                         const Vec3& u, double headroom);

// The largest sigma in [0, 1] with |(a + sigma b)_i| <= limit_i (1 - headroom) wherever b_i != 0
// allows it: each joint with b_i != 0 bounds sigma from above by (L_i - sign(b_i) a_i) / |b_i|;
// 0 when a bound is negative, 1 when none is below 1.
double feasible_feedforward_scale(const Vec6& a, const Vec6& b, const Vec6& torque_limit,
                                  double headroom);

// Caps the linear spring -k_lin (x2 - x1) of the proxy-side coupling (its f0) and +k_lin (x2 - x1)
// of the device-side one at `cap` [N] in magnitude, keeping its direction. Returns whether it
// bound (k_lin |x2 - x1| > cap); nothing changes otherwise.
bool cap_coupling_spring(double k_lin, const Vec3& x1, const Vec3& x2, double cap,
                         AffineWrench* proxy_side, Vec6* device_side);

}  // namespace dentsim
