// The virtual coupling's two wrenches of a tick in one pass, fast twin of reference/coupling.h's
// coupling_proxy_wrench_unchecked and coupling_device_wrench_unchecked (same equations (4.3)-(4.6),
// same operations on the same doubles: bitwise the reference's, tests/fast/coupling_test.cc).
//
// What the pair shares, computed once:
//   R12 = R1^T R2 and R21 = R2^T R1 are each other's transposes (the same products, summed in the
//   same order when Eigen does: checked at run time, entry by entry);
//   the SO(3) spring vectors' angle: with R12 = R21^T exactly, |vee(R12)| = |vee(R21)| (the same
//   entries up to sign) and tr R12 = tr R21 (the same diagonal), so rotation_angle and
//   half_angle_over_sin give the same phi and the same phi / (2 sin phi) for both, and
//   so3_spring_vector(R) = that factor times 2 vee(R) away from phi = pi (the logarithm's
//   branch, phi >= pi - 1e-3, calls the reference for each, as does a transpose that is not
//   exact): one atan2 and one sin a tick instead of two each;
//   G = -diag((k_lin T/2 + b_lin) I, (k_ang T/2 + b_ang) I) written entry by entry (its zeros are
//   -0.0, as the reference's -block_diag(...) gives) instead of built from two identities.
#pragma once

#include "reference/core/affine_wrench.h"
#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim::fast {

// T2_vc (the proxy side, affine in its velocity) and T1_vc (the device side), exactly as
// coupling_proxy_wrench_unchecked and coupling_device_wrench_unchecked (reference/coupling.h).
// Never throws, never allocates.
void coupling_wrenches_unchecked(const CouplingGains& g, const Pose& device, const Vec6& V1,
                                 const ProxyState& proxy, double T, Scheme scheme,
                                 AffineWrench* T2_vc, Vec6* T1_vc);

}  // namespace dentsim::fast
