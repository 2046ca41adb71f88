// The "field" contact model (issue #30; BEYOND THE THESIS; derivation in
// docs/derivations/field_contact.md): the surface proxy of the "sdf" model
// (reference/tooth/sdf.h, its algorithm in reference/tooth/surface_proxy_core.h) run on the
// sampled signed-distance field of the tooth's source surface (reference/tooth/sampled_field.h)
// instead of the exact distance to the voxel staircase. The tip's admissible set is
// A = {phi_field >= rho}; the sweep advances by (phi - (rho - s)) / L, L the field's Lipschitz
// constant, so g never enters {phi_field < rho - s} and so never crosses the field's solid
// {phi_field <= 0} (no tunnelling, docs/derivations/field_contact.md §3).
//
// Deep inside (all 8 corners of x's cell at the inside clamp, so no gradient), the query falls
// back to the exact voxel distance (reference/tooth/sdf.h) to find the way out: only a proxy that
// starts inside the tooth goes there.
//
// Materials stay per voxel: the contact's material is the solid voxel nearest to g (as "sdf").
// Drilling does not edit the field yet: the provider refuses "field" with drilling on
// (tooth_contacts.h), and the scene loader refuses the combination with a message.
#pragma once

#include "reference/tooth/sampled_field.h"
#include "reference/tooth/sdf.h"

namespace dentsim {

// The sampled field as the surface proxy's Solid (surface_proxy_core.h). Both must outlive it.
class FieldSolid {
 public:
  FieldSolid(const VoxelTooth& tooth, const SampledField& field) : tooth_(tooth), field_(field) {}

  const VoxelTooth& tooth() const { return tooth_; }
  const SampledField& field() const { return field_; }
  // phi_field(x) (found = false and phi = reach when phi >= reach), nearest = x - phi n; deep
  // inside, the exact voxel distance (header comment).
  SignedDistance distance(const Vec3& x, double reach) const;
  // grad phi / |grad phi| (deep inside or where the gradient vanishes: the voxel distance's).
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const;
  double lipschitz() const { return field_.lipschitz(); }

 private:
  const VoxelTooth& tooth_;
  const SampledField& field_;
};


}  // namespace dentsim
