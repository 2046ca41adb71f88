#include "reference/tooth/tooth_contacts.h"

#include <algorithm>

namespace dentsim {

ToothProviderBase::ToothProviderBase(const VoxelGrid& grid, ToolTip tip, double k_tooth,
                                     double b_tooth, const DrillParams* drill)
    : tip_(tip), k_tooth_(k_tooth), b_tooth_(b_tooth) {
  validate_tool_tip(tip_);
  if (drill != nullptr) {
    validate_drill_params(*drill);
    drills_ = true;
    drill_params_ = *drill;
    drill_state_ = make_drill_state(grid);
  }
  voxels_.reserve(kContactCapacity);
}

std::size_t ToothProviderBase::begin_query(std::vector<Contact>& out) {
  out.clear();
  voxels_.clear();
  return std::min(out.capacity(), voxels_.capacity());
}

bool ToothContactProvider::contacts(const Pose& proxy, std::vector<Contact>& out) {
  const std::size_t max_contacts = begin_query(out);
  return collide_tool_tip(tooth_, proxy, tip_, k_tooth_, b_tooth_, &scratch_, &out, &voxels_,
                          max_contacts);
}

int ToothContactProvider::drill(std::span<const Contact> contacts, double T) {
  if (!can_drill(contacts)) return 0;
  return drill_tick(contacts, voxels_, tip_, drill_params_, T, &tooth_, &drill_state_);
}

}  // namespace dentsim
