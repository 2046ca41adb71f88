// Collision of the tool-tip sphere with the voxel tooth -> contact set (thesis §2.5.2 "Collision
// Detection", §2.3 (2.15)-(2.16); docs/design.md "Voxel tooth").
//
// Frames and units: world frame {O}, metres. The tip is a sphere of radius rho [m] centred at
// c = x_2 + R_2 o, o the tip offset in the proxy body frame (zero: the tip is the proxy origin).
//
// Steps:
// 1. candidates: FullOctree::query_sphere(c, rho) -- descend from the root into occupied children
//    whose boxes intersect the sphere, down to the solid voxels the sphere intersects;
// 2. for every exposed face f of a candidate (NeighborCodes; faces shared with a solid neighbour
//    are skipped, so the edge between face-adjacent voxels gives no force), with face normal
//    n_f = face_normal(f) and signed distance d = n_f^T (c - p) of the centre outside the face
//    plane (p on the plane), |d| < rho:
//    - patch: the rectangle spanned by the runs of coplanar exposed faces through f along its two
//      in-plane axes; q = the point of the patch nearest to c (on the face plane);
//    - d > 0: n = (c - q) / |c - q|, depth = rho - |c - q|, taper t = n^T n_f = d / |c - q|
//      (over the patch n = n_f and depth = rho - d; past a patch edge or corner, the sphere-edge
//      contact, whose depth goes to 0 as the sphere leaves);
//    - d <= 0 (penetration >= rho): n = n_f, depth = rho - d if c projects onto the patch, else
//      the face is skipped;
//    - weight = t * area((face square) ∩ (disk where the plane cuts the sphere, radius
//      sqrt(rho^2 - d^2))), closed form disk_rect_area;
//    a face with weight > 0 emits
//      n,  x_o = q,  x_c = c - rho n (the deepest point of the sphere along -n),
//      r = R_2^T (x_c - x_2) = o - rho R_2^T n   (x_c = x_2 + R_2 r, body frame),
//      depth = n^T (x_o - x_c) > 0                                   (2.15 delta),
//      stiffness = K_tooth * stiffness_scale(material), damping = B_tooth * damping_scale,
//      weight [m^2], material id.
// The contact stage blends the set with weights normalised to sum 1 (params.h Contact): on a flat
// patch the weights partition the disk and all members share n and depth, so the force is
// K delta n whatever the resolution and wherever the sphere sits relative to voxel boundaries;
// weights, normals and depths are continuous in c while the penetration is below rho, so the
// blended force has no jump there (docs/tooth_octree.md: measured smoothness and resolution
// bounds, and the deep-penetration limit).
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "reference/core/params.h"
#include "reference/core/types.h"
#include "reference/tooth/neighbors.h"
#include "reference/tooth/octree.h"

namespace dentsim {

// The drillable tooth: octree (owning the grid) and neighbour codes (stored sparse: neighbors.h),
// kept consistent by reference/tooth/drilling.h.
struct VoxelTooth {
  FullOctree octree;
  SparseNeighborCodes codes;

  VoxelTooth() = default;
  explicit VoxelTooth(VoxelGrid grid);  // builds the octree and encodes every voxel
  const VoxelGrid& grid() const { return octree.grid(); }
};

struct ToolTip {
  double radius = 0.5e-3;           // rho [m], the bur radius
  Vec3 offset_body = Vec3::Zero();  // o: tip centre in the proxy body frame [m]
};

// Preallocated scratch of the collision stage (no allocation per tick once warmed up).
struct CollisionScratch {
  std::vector<std::size_t> candidates;
  CollisionScratch() { candidates.reserve(4096); }
};

// Throws InputError naming the field unless the tip radius is finite and > 0.
void validate_tool_tip(const ToolTip& tip);

// Area of the intersection of the disk of radius a centred at the origin with the rectangle
// [x0, x1] x [y0, y1] (x0 <= x1, y0 <= y1), exact (piecewise closed form); 0 for a <= 0.
double disk_rect_area(double a, double x0, double x1, double y0, double y1);

// Appends to `contacts` the contact set of the tip sphere at the proxy pose (steps above). If
// `contact_voxels` is not null, appends the flat voxel index of each contact in parallel.
// k_tooth [N/m], b_tooth [N s/m] are the scene's; throws InputError if rho <= 0. Stops and
// returns false when `contacts` would hold more than max_contacts members (the servo tick's
// fixed-capacity buffer: it never grows); true when the whole set was reported.
bool collide_tool_tip(const VoxelTooth& tooth, const Pose& proxy, const ToolTip& tip,
                      double k_tooth, double b_tooth, CollisionScratch* scratch,
                      std::vector<Contact>* contacts,
                      std::vector<std::size_t>* contact_voxels = nullptr,
                      std::size_t max_contacts = std::numeric_limits<std::size_t>::max());

// The static penalty force of one contact set blended as the contact stage does:
// f = sum_i w_i K_i depth_i n_i / sum_i w_i [N, world] (zero for an empty set). Used by drilling
// and tests; the contact stage itself adds damping and the PMI terms (2.16)-(2.19).
Vec3 blended_contact_force(const std::vector<Contact>& contacts);

}  // namespace dentsim
