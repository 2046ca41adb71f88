// The voxel tooth as the tick's collision and drilling stages: a ContactProvider
// (reference/core/contact_provider.h) over collide_tool_tip (reference/tooth/collision.h). It keeps
// the voxel index of every contact of the last query so that drilling
// (reference/tooth/drilling.h) can run on the same set after the solve.
#pragma once

#include <cstddef>
#include <vector>

#include "reference/core/contact_provider.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/drilling.h"

namespace dentsim {

class ToothContactProvider : public ContactProvider {
 public:
  // `tooth` must outlive the provider (drilling changes it); k_tooth [N/m] and b_tooth [N s/m]
  // are the scene's stiffness and damping (scaled per material by the collision stage). With
  // `drill` set the tool cuts the tooth (DrillParams validated here: InputError). Throws
  // InputError for a non-positive or non-finite tip radius.
  ToothContactProvider(VoxelTooth& tooth, ToolTip tip, double k_tooth, double b_tooth,
                       const DrillParams* drill = nullptr);

  bool contacts(const Pose& proxy, std::vector<Contact>& out) override;
  bool drills() const override { return drills_; }
  int drill(std::span<const Contact> contacts, double T) override;

  // Flat voxel index of each contact of the last query (parallel to its contact set).
  const std::vector<std::size_t>& contact_voxels() const { return voxels_; }
  const ToolTip& tip() const { return tip_; }
  const DrillState& drill_state() const { return drill_state_; }

 private:
  VoxelTooth& tooth_;
  ToolTip tip_;
  double k_tooth_, b_tooth_;
  bool drills_ = false;
  DrillParams drill_params_;
  DrillState drill_state_;
  CollisionScratch scratch_;
  std::vector<std::size_t> voxels_;
};

}  // namespace dentsim
