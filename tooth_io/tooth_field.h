// The sampled field (reference/tooth/sampled_field.h) of a scene's tooth, built from its source
// (tooth_io/tooth_source.h): the surface the "field" contact model touches (reference/tooth/
// field_contact.h; docs/derivations/field_contact.md).
#pragma once

#include "reference/core/types.h"
#include "reference/tooth/sampled_field.h"
#include "reference/tooth/voxel_grid.h"
#include "tooth_io/tooth_source.h"

namespace dentsim {

// The field of a scene's tooth (tooth_source.h) on its voxel grid `grid` (as built by
// build_tooth_grid from the same source, then moved by `offset` [m]): the procedural molar's
// implicit surface (triangulate_implicit of molar_solid) or the mesh's own triangles. Throws
// InputError for a volume source (its iso-surface field is not built yet) or bad input.
SampledField build_tooth_field(const ToothSource& source, const VoxelGrid& grid,
                               const Vec3& offset, const FieldBand& band);

}  // namespace dentsim
