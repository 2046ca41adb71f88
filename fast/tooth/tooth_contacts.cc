#include "fast/tooth/tooth_contacts.h"

namespace dentsim::fast {

bool ToothContactProvider::contacts(const Pose& proxy, std::vector<Contact>& out) {
  const std::size_t max_contacts = begin_query(out);
  return collide_tool_tip(tooth_, proxy, tip_, k_tooth_, b_tooth_, &out, &voxels_, max_contacts);
}

int ToothContactProvider::drill(std::span<const Contact> contacts, double T) {
  if (!can_drill(contacts)) return 0;
  const std::array<std::int64_t, kMaterialCount> removed_before = drill_state_.removed_voxels;
  const bool pulp_before = drill_state_.pulp_exposed;
  const std::uint8_t material = heaviest_material(contacts);
  const int removed =
      drill_tick(contacts, voxels_, tip_, drill_params_, T, &tooth_, &drill_state_, &removed_);
  record_drill(contacts, material, removed_before, pulp_before);
  return removed;
}

}  // namespace dentsim::fast
