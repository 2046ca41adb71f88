// Mesh -> voxel tooth (thesis §2.5.2, Fig. 2.9: voxelised surface model -> 3D seed filling ->
// materials; docs/design.md "Voxel tooth"; issue #4).
//
// Pipeline, each stage a free function so tests can check it alone:
//  1. surface_voxels: every voxel whose closed box meets a triangle, by the exact separating-axis
//     triangle/box test of Akenine-Möller ("Fast 3D Triangle-Box Overlap Testing", JGT 2001),
//     visiting only the voxels of each triangle's bounding box.
//  2. seed_fill_outside: 3D seed fill (6-connected, span-wise) of the outside, seeded from every
//     grid-boundary voxel that is not a surface voxel. The surface voxels of a closed surface
//     separate inside from outside (a centre-to-centre step between an inside and an outside
//     voxel crosses the surface inside one of the two closed boxes), so a torus's hole, being
//     outside, is reached and stays empty. Interior = neither outside nor surface.
//  3. center_winding_inside: which voxel centres have a non-zero winding number (one scanline per
//     grid row, robust at edges/vertices by symbolic perturbation, mesh.h). A surface voxel is
//     solid iff its centre is inside, so the error per surface voxel is below one voxel volume and
//     mostly cancels: |V_voxels - V_mesh| <= N_surface h^3 (the discretisation bound the tests
//     use).
//  4. assign_materials: pulp = solid voxels inside the mesh's pulp group (`Nerve`/`pulp`, by its
//     own stages 1-3) or the procedural pulp; enamel = solid voxels on the crown whose depth below
//     the outer surface (exact Euclidean distance transform to the nearest empty voxel, minus half
//     a voxel) is below t(s), s the height above the cemento-enamel junction (CEJ):
//     t(s) = min(t_cusp, t_top s / H), H the crown height, t_top = t_cusp H / (H - t_cusp): zero at
//     the CEJ, growing linearly to t_cusp at s = H - t_cusp, so that straight down from the crown's
//     top (s = H) the enamel is t_cusp thick (at depth t_cusp, t = t_cusp) and the lateral enamel
//     at mid-crown is t_top / 2 (1.9 mm for t_cusp = 2.5 mm, H = 7.5 mm). dentin = the rest.
//
// Units: metres, world frame {O}; the grid is axis-aligned (voxel_grid.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tooth_io/mesh.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

// Akenine-Möller SAT test: does the closed box centre +- half meet triangle (a, b, c)? Touching
// counts as overlap.
bool triangle_box_overlap(const Vec3& center, const Vec3& half, const Vec3& a, const Vec3& b,
                          const Vec3& c);

// An empty N^3 grid (N a power of two, 4..1024, else InputError) centred on `bounds`, with voxel
// size chosen so the largest extent spans N - 2 * margin_voxels voxels.
VoxelGrid make_grid(const Aabb& bounds, int resolution, int margin_voxels = 2);

// Stage 1: 1 where a listed triangle (all when empty) meets the voxel, else 0. N^3, flat index.
std::vector<std::uint8_t> surface_voxels(const TriangleMesh& mesh, const VoxelGrid& grid,
                                         const std::vector<int>& triangles = {});

// Stage 2: 1 for voxels 6-connected to the grid boundary through non-barrier voxels, else 0.
std::vector<std::uint8_t> seed_fill_outside(const std::vector<std::uint8_t>& barrier, int n);

// Stage 3: 1 where the voxel centre has non-zero winding w.r.t. the listed triangles.
std::vector<std::uint8_t> center_winding_inside(const TriangleMesh& mesh, const VoxelGrid& grid,
                                                const std::vector<int>& triangles = {});

struct SolidStats {
  long surface_voxels = 0;
  long outside_voxels = 0;
  long interior_voxels = 0;       // not outside, not surface
  long surface_solid_voxels = 0;  // surface voxels whose centre is inside
  long solid_voxels() const { return interior_voxels + surface_solid_voxels; }
};

// Stages 1-3: 1 for solid voxels of the listed triangles' solid.
std::vector<std::uint8_t> voxelize_solid(const TriangleMesh& mesh, const VoxelGrid& grid,
                                         const std::vector<int>& triangles = {},
                                         SolidStats* stats = nullptr);

// The crown's direction and the CEJ: height s(p) = axis . p - cej [m] is >= 0 on the crown.
struct CrownFrame {
  Vec3 axis = Vec3::UnitZ();  // unit, from the roots towards the occlusal surface
  double cej = 0.0;           // axis . p at the cemento-enamel junction [m]
  double crown_height = 7.5e-3;
};

// For a mesh without anatomy: the long axis is the solid's longest bounding-box axis; the crown
// is the end whose last 15 % of the length holds more solid voxels (crowns are bulkier than root
// tips); the CEJ lies `crown_fraction` of the length from that end.
CrownFrame estimate_crown_frame(const std::vector<std::uint8_t>& solid, const VoxelGrid& grid,
                                double crown_fraction);

// Stage 4: `grid.voxels` holds the solid (non-zero = solid) on entry and materials on exit.
// `pulp` (N^3, may be empty) marks pulp voxels; so does kPulp in `grid.voxels` on entry (the
// procedural molar marks its pulp there: no second N^3 array, 128 MiB at 512^3; issue #30).
// `enamel_cusp_m` is t_cusp above (t_top is unbounded when t_cusp >= H: the whole crown is enamel).
void assign_materials(VoxelGrid& grid, const std::vector<std::uint8_t>& pulp,
                      const CrownFrame& crown, double enamel_cusp_m);

// Squared Euclidean distance [voxels^2] from each voxel centre to the nearest empty voxel centre,
// clipped at clip^2 (values >= clip^2 mean "at least clip"). Exact below the clip (separable
// lower-envelope transform of Felzenszwalb & Huttenlocher, Theory of Computing 2012).
std::vector<std::uint16_t> distance_to_empty_sq(const VoxelGrid& grid, int clip);

struct VoxelizeOptions {
  int resolution = 128;
  int margin_voxels = 2;
  double enamel_cusp_m = 2.5e-3;       // t_cusp (procedural_molar.h cites the source)
  double crown_fraction = 7.5 / 21.5;  // crown height / tooth length of a lower first molar
};

struct VoxelizeReport {
  SolidStats solid;
  long pulp_voxels = 0;
  std::vector<std::string> pulp_groups;  // mesh groups mapped to pulp
  CrownFrame crown;
};

// Stages 1-4 on a closed mesh in metres. Groups named `Nerve` or `pulp` (any case) become pulp.
VoxelGrid voxelize_mesh(const TriangleMesh& mesh, const VoxelizeOptions& options,
                        VoxelizeReport* report = nullptr);

// Voxel counts per material id (index = Material).
std::vector<long> count_materials(const VoxelGrid& grid);

}  // namespace dentsim
