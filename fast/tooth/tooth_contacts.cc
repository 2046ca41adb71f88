#include "fast/tooth/tooth_contacts.h"

namespace dentsim::fast {

bool ToothContactProvider::contacts(const Pose& proxy, std::vector<Contact>& out) {
  const std::size_t max_contacts = begin_query(out);
  return collide_tool_tip(tooth_, proxy, tip_, k_tooth_, b_tooth_, &out, &voxels_, max_contacts);
}

int ToothContactProvider::drill(std::span<const Contact> contacts, double T) {
  if (!can_drill(contacts)) return 0;
  return drill_tick(contacts, voxels_, tip_, drill_params_, T, &tooth_, &drill_state_);
}

}  // namespace dentsim::fast
