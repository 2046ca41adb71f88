// The fast voxel tooth as the tick's collision and drilling stages: the twin of
// reference/tooth/tooth_contacts.h over fast::collide_tool_tip and fast::drill_tick. Same
// contract (reference/core/contact_provider.h): contacts() fills the tick's fixed-capacity buffer
// and returns false when the set does not fit; neither contacts() nor drill() allocates or throws
// once constructed (tests/fast/tooth_contacts_test.cc counts allocations).
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "fast/tooth/brick_tooth.h"
#include "fast/tooth/collision.h"
#include "fast/tooth/cut_set.h"
#include "fast/tooth/drilling.h"
#include "fast/tooth/sdf.h"
#include "reference/tooth/tooth_contacts.h"

namespace dentsim::fast {

class ToothContactProvider : public ToothProviderBase {
 public:
  // As dentsim::ToothContactProvider: `tooth` must outlive the provider; throws InputError for a
  // non-positive or non-finite tip radius or invalid drill params.
  ToothContactProvider(BrickTooth& tooth, ToolTip tip, double k_tooth, double b_tooth,
                       const DrillParams* drill = nullptr)
      : ToothProviderBase(tooth.grid(), tip, k_tooth, b_tooth, drill), tooth_(tooth) {}

  bool contacts(const Pose& proxy, std::vector<Contact>& out) override;
  int drill(std::span<const Contact> contacts, double T) override;
  const BrickTooth& tooth() const { return tooth_; }

 private:
  BrickTooth& tooth_;
};

// The surface-proxy contact ("sdf") of the fast pipeline: the reference's provider with
// fast::signed_distance, whose proxy update runs on RecallingVoxelSolid (fast/tooth/sdf.h: the
// same answers, the repeated ones remembered), so g is bitwise the reference's, and whose cut set
// and material come from the surface voxels (CutSetProvider, fast/tooth/cut_set.h). With skips on
// (PipelineToothSetup::skip_unneeded) the solid keeps a free-space certificate across ticks
// (fast/tooth/sdf.h FreeSpaceCertificate: no octree query while the tip is farther from the tooth
// than its travel since the last exact one). Its outside searches are local (fast/tooth/sdf.h
// LocalVoxelDistance on the cut set's surface bits, its last answer's voxel kept across ticks),
// the octree's where the local query cannot certify its answer; the answers its solid remembers
// are kept from tick to tick (RecalledAnswers).
class SdfContactProvider final : public CutSetProvider {
 public:
  SdfContactProvider(VoxelTooth& tooth, const PipelineToothSetup& setup);
  const FreeSpaceCertificate& certificate() const { return certificate_; }
  const LocalVoxelDistance& local_distance() const { return local_; }

 protected:
  const Vec3& update_sdf_proxy(SurfaceProxy* proxy, const Vec3& c) override;

 private:
  const VoxelTooth& tooth_;
  FreeSpaceCertificate certificate_;
  bool certify_;
  LocalVoxelDistance local_;
  RecalledAnswers answers_;  // the proxy's solid's, kept across updates
};

// The fast pipeline's tooth (fast/registry.h): for the face model the brick tooth, built from
// the reference tooth's grid and drilled by fast::ToothContactProvider; for the surface proxy
// SdfContactProvider (above); for the field model fast::FieldContactProvider (fast/tooth/field.h).
std::unique_ptr<PipelineTooth> make_fast_tooth(VoxelTooth& tooth, const PipelineToothSetup& setup);

// The face model's fast tooth, for tests that reach its brick tooth (its free-space early out).
class BrickPipelineTooth final : public PipelineTooth {
 public:
  BrickPipelineTooth(const VoxelTooth& tooth, const PipelineToothSetup& setup);
  ToothProviderBase& provider() override { return provider_; }
  const VoxelGrid& grid() const override { return brick_.grid(); }
  void tip_contacts(const Pose& pose, std::vector<Contact>* out) override;
  BrickTooth& brick() { return brick_; }

 private:
  BrickTooth brick_;
  PipelineToothSetup setup_;
  ToothContactProvider provider_;
};

}  // namespace dentsim::fast
