// The voxel tooth as the tick's collision stage: a ContactProvider (reference/tick.h) over
// collide_tool_tip (reference/tooth/collision.h). It keeps the voxel index of every contact of
// the last query so that drilling (reference/tooth/drilling.h) can run after the tick.
#pragma once

#include <cstddef>
#include <vector>

#include "reference/tick.h"
#include "reference/tooth/collision.h"

namespace dentsim {

class ToothContactProvider : public ContactProvider {
 public:
  // `tooth` must outlive the provider; k_tooth [N/m] and b_tooth [N s/m] are the scene's
  // stiffness and damping (scaled per material by the collision stage).
  ToothContactProvider(const VoxelTooth& tooth, ToolTip tip, double k_tooth, double b_tooth);

  void contacts(const Pose& proxy, std::vector<Contact>& out) override;

  // Flat voxel index of each contact of the last query (parallel to its contact set).
  const std::vector<std::size_t>& contact_voxels() const { return voxels_; }
  const ToolTip& tip() const { return tip_; }

 private:
  const VoxelTooth& tooth_;
  ToolTip tip_;
  double k_tooth_, b_tooth_;
  CollisionScratch scratch_;
  std::vector<std::size_t> voxels_;
};

}  // namespace dentsim
