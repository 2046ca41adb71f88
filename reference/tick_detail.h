// The assemble stage with its decomposition step as a parameter: shared by reference/tick.cc and
// fast/tick.cc only (kept out of reference/tick.h, which most of the project includes).
#pragma once

#include "reference/core/pipeline.h"

namespace dentsim::reference::detail {

// The passive decomposition's feed-forward (4.7) of a pmi-pd tick: fills d.pd_T1 and d.pd_T2 from
// the device inertia under the hypothesis in force, the poses, r.V1, r.F1_hat and d.contact;
// false when the locked inertia is not positive definite (or phi is not finite).
using PdStep = bool (*)(const PipelineModel& m, PipelineData& d);

// The reference's step: decompose_locked + pd_feedforward (reference/decomposition.h).
bool pd_step(const PipelineModel& m, PipelineData& d);

// assemble with d.contact already computed and `pd` for the decomposition (pmi-pd only).
TickStatus assemble_given_contact_with(const PipelineModel& m, PipelineData& d, PdStep pd);

}  // namespace dentsim::reference::detail
