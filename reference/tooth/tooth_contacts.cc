#include "reference/tooth/tooth_contacts.h"

namespace dentsim {

ToothContactProvider::ToothContactProvider(const VoxelTooth& tooth, ToolTip tip, double k_tooth,
                                           double b_tooth)
    : tooth_(tooth), tip_(tip), k_tooth_(k_tooth), b_tooth_(b_tooth) {
  voxels_.reserve(4096);
}

void ToothContactProvider::contacts(const Pose& proxy, std::vector<Contact>& out) {
  out.clear();
  voxels_.clear();
  collide_tool_tip(tooth_, proxy, tip_, k_tooth_, b_tooth_, &scratch_, &out, &voxels_);
}

}  // namespace dentsim
