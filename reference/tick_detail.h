// The assemble stage with its decomposition step as a parameter: shared by reference/tick.cc and
// fast/tick.cc only (kept out of reference/tick.h, which most of the project includes).
#pragma once

#include "reference/core/pipeline.h"

namespace dentsim::reference::detail {

// True when every entry of every argument is finite: the same answer as each one's allFinite(),
// in one multiply and one add an entry (vectorised) where allFinite() compares and branches on
// each. x * 0 is +-0 for a finite x and NaN for an infinite or NaN one, and a sum of signed zeros
// is a zero, so the sum is zero exactly when every entry is finite.
template <typename... Ms>
inline bool all_finite(const Ms&... ms) {
  double zeros = 0.0;
  ((zeros += (ms.array() * 0.0).sum()), ...);
  return zeros == 0.0;
}

// The device's joint-space inertia under the hypothesis in force of the grip detector: M, plus the
// hand's M_hand while the hand is judged on the tool (grasp on). The one place that picks it: the
// encoder Kalman filter, the loop-lag compensation and the reference's decomposition read it here
// (the fast twin's decomposition adds the hand at the tool, Mt, fast/tick.cc pd_step).
inline Mat6 model_joint_inertia(const PipelineModel& m, const PipelineData& d, const Mat6& M) {
  Mat6 out = M;
  if (m.grasp && d.grip.gripped) out += d.M_hand;
  return out;
}

// J1 = J_t^-1 (2.2) into d.J1 (the inverse a tick needs: observer wrench, device inertia), with
// d.dev the terms J_t came from; the reference's with Eigen's partial-pivoting LU, the fast
// twin's on the device's block structure when it has one (fast/phantom) or fast/dense6.h's LU.
using InvertJacobian = void (*)(const PipelineModel& m, const Mat6& J_t, PipelineData& d);

// x = M^-1 b for the device's joint inertia M (symmetric); false when M is not positive definite
// (x then unspecified). The reference's with Eigen's LLT, the fast twin's with fast/dense6.h's.
using SolveInertia = bool (*)(const Mat6& M, const Vec6& b, Vec6* x);

// device_terms (reference/tick.h) with the Jacobian's inverse and the inertia's solve (the model
// acceleration of the encoder Kalman filter and of the loop-lag compensation) as parameters.
TickStatus device_terms_with(const PipelineModel& m, PipelineData& d, InvertJacobian invert,
                             SolveInertia solve);

// The grip detector's filter step of the observe stage (grasp on): d.grip from the two
// hypotheses' estimates h0, h1 over the tick that just ended (d.T_last); returns whether the hand
// is judged on the tool. The reference's evaluates the filter's gains each tick; the fast twin's
// keeps them by tick length (GripGainMemo): the same doubles.
using GripUpdate = bool (*)(const PipelineModel& m, PipelineData& d, const Vec6& h0,
                            const Vec6& h1);

// observe (reference/tick.h) with the grip filter's step as a parameter.
TickStatus observe_with(const PipelineModel& m, PipelineData& d, GripUpdate grip);

// The passive decomposition's feed-forward (4.7) of a pmi-pd tick: fills d.pd_T1 (or its factors,
// PipelineData::pd_T1_factored) and d.pd_T2 from the device inertia under the hypothesis in
// force, the poses, r.V1, r.F1_hat and d.contact; false when the locked inertia is not positive
// definite (or phi is not finite).
using PdStep = bool (*)(const PipelineModel& m, PipelineData& d);

// The reference's step: decompose_locked + pd_feedforward (reference/decomposition.h).
bool pd_step(const PipelineModel& m, PipelineData& d);

// assemble with d.contact already computed and `pd` for the decomposition (pmi-pd only).
TickStatus assemble_given_contact_with(const PipelineModel& m, PipelineData& d, PdStep pd);

}  // namespace dentsim::reference::detail
