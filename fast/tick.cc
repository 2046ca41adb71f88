#include "fast/tick.h"

#include "fast/contact.h"
#include "fast/pmi.h"

namespace dentsim::fast {

// The device model does the work (fast::PhantomModel with the fast pipeline); the stage around it
// (finite checks, J1 = J_t^-1, V1, the hand's terms) is the reference's.
TickStatus device_terms(const PipelineModel& m, PipelineData& d) {
  return reference::device_terms(m, d);
}

// Two 6-vector observer updates: already allocation-free and O(36) flops; shared.
TickStatus observe(const PipelineModel& m, PipelineData& d) { return reference::observe(m, d); }

// The environment does the work (fast::ToothContactProvider with the fast pipeline).
TickStatus collide(const PipelineModel& m, PipelineData& d) { return reference::collide(m, d); }

TickStatus assemble(const PipelineModel& m, PipelineData& d) {
  if (d.r.contacts.empty()) {
    d.contact = AffineWrench{};
  } else {
    d.contact = fast::contact_wrench_unchecked(d.r.contacts, d.proxy.pose, d.T, m.scheme);
  }
  return reference::detail::assemble_given_contact(m, d);
}

TickStatus solve(const PipelineModel& m, PipelineData& d) {
  return reference::detail::solve_with(m, d, fast::pmi_try_solve);
}

TickStatus command(const PipelineModel& m, PipelineData& d) { return reference::command(m, d); }

TickStatus drill(const PipelineModel& m, PipelineData& d) { return reference::drill(m, d); }

TickStatus reset(const PipelineModel& m, PipelineData& d) { return reference::reset(m, d); }

const StageTable& fast_stage_table() {
  static const StageTable kTable = {
      "fast", {device_terms, observe, collide, assemble, solve, command, drill}, reset};
  return kTable;
}

}  // namespace dentsim::fast
