// The sampled field (reference/tooth/sampled_field.h) of a scene's tooth, built from its source
// (tooth_io/tooth_source.h): the surface the "field" contact model touches (reference/tooth/
// field_contact.h; docs/derivations/field_contact.md).
//
// The surface, by source: the procedural molar's implicit surface (triangulate_implicit of
// molar_solid), the mesh's own triangles, or a scan's iso-surface (scan_surface below). In every
// case the field's sign at a voxel centre is the grid's (solid -> negative), and the surface runs
// between the solid and empty centres, so the field's solid is the grid's at every voxel centre.
//
// The scan's surface (issue #30: "the iso-surface of the (resampled) intensity at the material
// threshold; partial volume gives the sub-voxel position"; derivation and measured figures in
// docs/derivations/field_contact.md §1 "scan"):
//  - Which surface: where the class steps 3-4 of build_volume_tooth give the scan's intensity
//    changes between solid and background (VolumeSolidRule: the thresholds, and step 4's
//    (mean enamel + mean background) / 2 on an enamel/background edge), the intensity being
//    sample_trilinear of the scan, the very function build_volume_tooth resamples at the voxel
//    centres. So the surface's two sides are the grid's classes wherever the grid follows the
//    intensity, and partial volume places it: a sample is the mean of its own box, so across a
//    face the samples form a ramp one scan spacing D wide centred on the face, and the level
//    halfway between the two sides' intensities is crossed on the face; trilinear interpolation
//    of the ramp's samples crosses it within (3/2 - sqrt 2) D = 0.086 D of the face when the face
//    is normal to a scan axis (no orientation of 4000 swept did worse), whatever the grid's h.
//  - How: marching tetrahedra over the grid's voxel centres with the grid's own solid voxels as
//    the signs (triangulate_voxel_signs), so only the components the grid keeps have a surface
//    (islands it dropped, speckle outside the grid have none; pulp is solid, as in the grid), and
//    each vertex on its edge where the rule above changes, by bisection of the intensity along
//    the edge (to 2^-40 of it): the vertex is on the iso-surface itself, not on a second linear
//    interpolation of the two centres' values. An edge whose two ends the rule does not separate
//    (the grid changed a class there: an island relabelled, pulp next to the outside through a
//    diagonal, a class at the grid's boundary) takes its midpoint, the staircase's own place.
//  - Error against the true surface (the shape the partial-volume scan was taken of): the
//    iso-surface's (0.086 D on flat faces, plus O(D^2 / R) on a surface of radius R), the
//    triangles' chord (zero on flat faces, <= 3 h^2 / (8 R)) and the field's interpolation of the
//    distance to them (zero on flat faces; the sphere bound of sampled_field.h); against the
//    voxel staircase's up to h / 2.
#pragma once

#include "reference/core/types.h"
#include "reference/tooth/sampled_field.h"
#include "reference/tooth/triangle_mesh.h"
#include "reference/tooth/voxel_grid.h"
#include "tooth_io/tooth_source.h"
#include "tooth_io/volume.h"

namespace dentsim {

// The field of a scene's tooth (tooth_source.h) on its voxel grid `grid` (as built by
// build_tooth_grid from the same source, then moved by `offset` [m]). Throws InputError for bad
// input (naming the file).
SampledField build_tooth_field(const ToothSource& source, const VoxelGrid& grid,
                               const Vec3& offset, const FieldBand& band);

// How the scan's surface vertices were placed: `edges` surface edges (one vertex each), of which
// `midpoint` at the edge's middle (the rule does not separate the edge's ends; header comment).
struct ScanSurfaceStats {
  long edges = 0;
  long midpoint = 0;
};

// The scan's surface (header comment) in the scanner frame: `grid` and `rule` as
// build_volume_tooth(volume, ...) made them.
TriangleMesh scan_surface(const ScanVolume& volume, const VoxelGrid& grid,
                          const VolumeSolidRule& rule, ScanSurfaceStats* stats = nullptr);

// The field of a scan on `grid`, the grid build_volume_tooth(volume, options) gives, moved by
// `offset` [m]. Throws InputError naming the volume's source: a degenerate volume, no sample in
// the enamel or dentin ranges, no sample of background (the thresholds at or below the scan's
// lowest intensity: no surface between tooth and background), no solid voxel after resampling,
// or a grid that is not this scan's (the file changed between the two builds).
SampledField build_volume_field(const ScanVolume& volume, const VolumeToothOptions& options,
                                const VoxelGrid& grid, const Vec3& offset, const FieldBand& band,
                                ScanSurfaceStats* stats = nullptr);

}  // namespace dentsim
