// The penalty contact of a contact set as an affine wrench, fast twin of reference/contact.h's
// contact_wrench_unchecked (same equations (2.15)-(2.19), (4.9); same weights ContactWeights).
//
// Each penetrating member contributes through the 6-vector a_i = J_c,i^T n_i = [n_i; r_i x (R^T
// n_i)] (the wrench of a unit force along n_i at x_c,i; d(delta_i)/dt = -a_i^T V), so
//     f0 = sum_i a_i (k_i delta_i),   G = -sum_i g_i a_i a_i^T,
//     k_i = w_i K_i,  g_i = w_i (K_i T/2 [kMidpoint] + B_i)
// — a symmetric rank-1 update per member in place of the reference's 3x6 / 6x3 products (the
// same sums, in another order: equal within the tolerance policy, tests/fast/tick_test.cc).
#pragma once

#include <span>

#include "reference/contact.h"
#include "reference/core/affine_wrench.h"
#include "reference/core/params.h"

namespace dentsim::fast {

AffineWrench contact_wrench_unchecked(std::span<const Contact> contacts, const Pose& proxy,
                                      double T, Scheme scheme);

// Twin of reference/contact.h's add_anchored_spring_unchecked (same K_imp, same b_t from
// reference's anchored_spring_damping): -K_imp T/2 b_j b_j^T for two tangents t_j of n,
// b_j = J_o^T t_j = [t_j; o x (R^T t_j)] (I - n n^T = t1 t1^T + t2 t2^T).
void add_anchored_spring_unchecked(AffineWrench* F, std::span<const Contact> contacts,
                                   const Pose& proxy, double T, Scheme scheme,
                                   const AnchoredSpring& spring, double b_lin, double b_ang);

}  // namespace dentsim::fast
