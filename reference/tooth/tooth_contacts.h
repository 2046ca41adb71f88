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

// What the reference and the fast tooth providers (fast/tooth/tooth_contacts.h) share: the tip,
// the scene's stiffness and damping, the drill parameters and state, and the voxel index of each
// contact of the last query. The constructor validates the tip and the drill parameters
// (InputError) and sizes the buffers, so the tick itself neither throws nor allocates.
class ToothProviderBase : public ContactProvider {
 public:
  bool drills() const override { return drills_; }
  // Flat voxel index of each contact of the last query (parallel to its contact set).
  const std::vector<std::size_t>& contact_voxels() const { return voxels_; }
  const ToolTip& tip() const { return tip_; }
  const DrillState& drill_state() const { return drill_state_; }

 protected:
  // `grid`: the tooth's grid (sizes the drill state when `drill` is set).
  ToothProviderBase(const VoxelGrid& grid, ToolTip tip, double k_tooth, double b_tooth,
                    const DrillParams* drill);
  // Clears `out` and the voxel list; returns the most members the query may report (the smaller
  // capacity of the two, which never grow).
  std::size_t begin_query(std::vector<Contact>& out);
  // Whether drill() has a set to cut: drilling on and `contacts` the last query's nonempty set.
  bool can_drill(std::span<const Contact> contacts) const {
    return drills_ && !contacts.empty() && contacts.size() == voxels_.size();
  }

  ToolTip tip_;
  double k_tooth_, b_tooth_;
  bool drills_ = false;
  DrillParams drill_params_;
  DrillState drill_state_;
  std::vector<std::size_t> voxels_;
};

class ToothContactProvider : public ToothProviderBase {
 public:
  // `tooth` must outlive the provider (drilling changes it); k_tooth [N/m] and b_tooth [N s/m]
  // are the scene's stiffness and damping (scaled per material by the collision stage). With
  // `drill` set the tool cuts the tooth (DrillParams validated here: InputError). Throws
  // InputError for a non-positive or non-finite tip radius.
  ToothContactProvider(VoxelTooth& tooth, ToolTip tip, double k_tooth, double b_tooth,
                       const DrillParams* drill = nullptr)
      : ToothProviderBase(tooth.grid(), tip, k_tooth, b_tooth, drill), tooth_(tooth) {}

  bool contacts(const Pose& proxy, std::vector<Contact>& out) override;
  int drill(std::span<const Contact> contacts, double T) override;

 private:
  VoxelTooth& tooth_;
  CollisionScratch scratch_;
};

}  // namespace dentsim
