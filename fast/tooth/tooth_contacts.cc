#include "fast/tooth/tooth_contacts.h"

#include "fast/tooth/field.h"
#include "fast/tooth/sdf.h"
#include "reference/tooth/surface_proxy_core.h"

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

BrickPipelineTooth::BrickPipelineTooth(const VoxelTooth& tooth, const PipelineToothSetup& setup)
    : brick_(tooth),
      setup_(setup),
      provider_(brick_, setup.tip, setup.k_tooth, setup.b_tooth, setup.drilling) {
  brick_.set_free_space_early_out(setup.skip_unneeded);
}

void BrickPipelineTooth::tip_contacts(const Pose& pose, std::vector<Contact>* out) {
  out->clear();
  collide_tool_tip(brick_, pose, setup_.tip, setup_.k_tooth, setup_.b_tooth, out);
}

SdfContactProvider::SdfContactProvider(VoxelTooth& tooth, const PipelineToothSetup& setup)
    : CutSetProvider(tooth, setup.tip, setup.k_tooth, setup.b_tooth, setup.drilling,
                     ContactModel::kSurfaceProxy, &fast::signed_distance),
      tooth_(tooth),
      certify_(setup.skip_unneeded),
      local_(tooth, cut_set().surface()) {}

// The `sdf` model's Solid takes the thesis's steps only (surface_proxy_core.h: no field-only
// path), as the reference's VoxelSolid (reference/tooth/sdf.cc).
static_assert(!proxy_detail::kFieldPaths<RecallingVoxelSolid>);

const Vec3& SdfContactProvider::update_sdf_proxy(SurfaceProxy* proxy, const Vec3& c) {
  // One update: the tooth does not change within it (the certificate, the local query's last voxel
  // and the remembered answers outlive it: drilling only removes voxels).
  const RecallingVoxelSolid solid(tooth_, certify_ ? &certificate_ : nullptr, &local_, &answers_);
  return proxy->update_on(solid, c);
}

std::unique_ptr<PipelineTooth> make_fast_tooth(VoxelTooth& tooth, const PipelineToothSetup& setup) {
  if (setup.contact_model == ContactModel::kFaces) {
    return std::make_unique<BrickPipelineTooth>(tooth, setup);
  }
  if (setup.contact_model == ContactModel::kField) return make_fast_field_tooth(tooth, setup);
  return std::make_unique<ProviderTooth<SdfContactProvider>>(tooth, setup, tooth, setup);
}

}  // namespace dentsim::fast
