// The fast servo tick: the stage list of reference/core/pipeline.h, name for name, over the same
// PipelineModel and PipelineData (the twin of reference/tick.h). Registered as "fast" in
// fast/registry.h, which drives the differential tests (tests/fast/tick_test.cc, `dentsim
// crosscheck fast`) and the benchmarks.
//
// Where the work is, and what fast/ does about it:
//   device_terms  the device model's one pass: with the fast pipeline the model is
//                 fast::PhantomModel (fast/phantom/), specialised to the Phantom's tree; the
//                 encoder Kalman filter two joints at a time (fast/encoder_kalman.h) and the
//                 hand's terms (fast/grasp_mass_model.h), bitwise the reference's
//   collide       the environment's query: fast::ToothContactProvider (fast/tooth/)
//   assemble      the contact wrench as symmetric rank-1 updates (fast/contact.h); both coupling
//                 wrenches in one pass (fast/coupling.h, bitwise); the pmi-pd feed-forward on its
//                 block structure (fast/decomposition.h)
//   solve         partial-pivoting LU of the scaled PMI system (fast/pmi.h)
//   drill         the environment's cut: fast::drill_tick through the fast provider
// The stage code itself is shared with the reference where nothing faster exists (observe,
// command, solve around its kernel, device_terms with loop-lag compensation or the stick-slip
// filter, assemble while the shape control is engaged: reference/tick.h `detail`), so the two
// cannot drift apart. Skips: a stage returns at once when the scene does not need it (no observer
// without a gain, no decomposition unless pmi-pd, no friction without mu, no drill unless the
// environment drills, no contact work on an empty set).
#pragma once

#include "reference/tick.h"

namespace dentsim::fast {

TickStatus device_terms(const PipelineModel& m, PipelineData& d);
TickStatus observe(const PipelineModel& m, PipelineData& d);
TickStatus collide(const PipelineModel& m, PipelineData& d);
TickStatus assemble(const PipelineModel& m, PipelineData& d);
TickStatus solve(const PipelineModel& m, PipelineData& d);
TickStatus command(const PipelineModel& m, PipelineData& d);
TickStatus drill(const PipelineModel& m, PipelineData& d);
TickStatus reset(const PipelineModel& m, PipelineData& d);

const StageTable& fast_stage_table();

// The grip filter's step of the fast observe stage: reference/grip_detector.h's
// grip_filter_update with its three gains (three exp) looked up by T in `memo` and evaluated only
// for a T not kept there (GripGainMemo, reference/core/pipeline.h): the same doubles as the
// reference's step (tests/fast/observe_test.cc). No allocation, no throw.
bool grip_filter_update_kept(const GripDetectorParams& p, const Vec6& norm, GripFilterState& s,
                             GripGainMemo& memo, const Vec6& h0, const Vec6& h1, double T);

}  // namespace dentsim::fast
