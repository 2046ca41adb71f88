// The hand's terms of the grasp model, fast twin of reference/grasp_mass_model.h's
// grasp_mass_terms: M_h = J_t^T diag(Mt) J_t and C_h^T qd = dJ_t/dt^T (Mt .* V1), the same
// products summed in the same order as the reference's Eigen expressions, so bitwise the
// reference's (tests/fast/grasp_mass_model_test.cc). Eigen forms each entry as a dot product
// vectorised two terms at a time, p_k = (J(k, i) Mt_k) J(k, j) summed as
// (p0 + (p2 + p4)) + (p1 + (p3 + p5)); this twin forms two entries (rows i, i + 1) at a time, one
// per SSE2 lane, in that order, with W = J_t^T diag(Mt) formed once (the reference's product is
// evaluated through Eigen's generic small-product kernel). Without SSE2 it is the reference.
// Never allocates.
#pragma once

#include "reference/core/device_model.h"

namespace dentsim::fast {

void grasp_mass_terms(const Vec6& Mt, const DeviceTerms& base, const Vec6& V1, Mat6* M_hand,
                      Vec6* CTqd_hand);

}  // namespace dentsim::fast
