// Triangle meshes of teeth: loading (binary/ASCII STL, Wavefront OBJ), validation, volume and
// scaling (issue #4, "Tooth sources"; thesis §2.5.2: the voxel tooth starts from a surface model).
//
// Units and frames: vertices are in the mesh's own unit until scale_mesh() maps them to metres in
// the world frame {O}. STL and OBJ carry no unit, so a caller must choose a scale (metres per mesh
// unit) or a target size [m] and echo it (see docs/tooth_sources.md).
//
// Orientation: a valid closed shell has its triangles wound counter-clockwise seen from outside,
// so its signed volume (divergence theorem, V = 1/6 sum a . (b x c)) is positive. A shell nested
// inside another with the same orientation (the CHAI3D tooth's `Nerve` inside `Tooth0`) is a
// material region, not a cavity; an inward-wound nested shell is a cavity.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/triangle_mesh.h"

namespace dentsim {

// Largest |coordinate| a mesh may have, in its own units (and in metres after scaling): volumes
// are products of three coordinates, so 1e9 keeps every one far inside the range of a double.
inline constexpr double kMaxMeshCoordinate = 1e9;

// What loading and validation found; `repairs` lists every change made to the input (said loudly
// by the CLI). Edge counts are over undirected edges after welding.
struct MeshReport {
  int input_vertices = 0;
  int input_triangles = 0;
  int welded_vertices = 0;       // exact duplicate positions merged (STL stores none shared)
  int degenerate_triangles = 0;  // removed: a repeated vertex or zero area
  int boundary_edges = 0;        // used by one triangle: the mesh is open
  int nonmanifold_edges = 0;     // used by three or more triangles
  int inconsistent_edges = 0;    // used twice in the same direction: orientation flips
  int shells = 0;                // edge-connected components
  int flipped_shells = 0;        // inside-out outermost shells turned outward (a repair)
  std::vector<std::string> repairs;
};

struct LoadedMesh {
  TriangleMesh mesh;
  MeshReport report;
};

// Parsers over the file's bytes; `name` is used in error messages. Both weld exact duplicate
// vertices, drop degenerate triangles and validate (validate_and_repair below). Throw InputError
// naming the file, the line/triangle and what was expected.
LoadedMesh parse_stl(const std::string& bytes, const std::string& name);
LoadedMesh parse_obj(const std::string& text, const std::string& name);
// Reads `path` and dispatches on the extension (.stl, .obj; case-insensitive).
LoadedMesh load_mesh(const std::string& path);

// Welds exact duplicate vertices, removes degenerate triangles, checks that every edge is shared
// by exactly two triangles in opposite directions, and turns inside-out outermost shells outward.
// Throws InputError (naming `name` and the edge counts) for an empty, non-finite, too large
// (|coordinate| > kMaxMeshCoordinate), open, non-manifold or inconsistently oriented mesh.
MeshReport validate_and_repair(TriangleMesh& mesh, const std::string& name);

// Signed volume of the triangles listed (all when `triangles` is empty), divergence theorem.
double signed_volume(const TriangleMesh& mesh, const std::vector<int>& triangles = {});

// Edge-connected shells: triangle index lists.
std::vector<std::vector<int>> mesh_shells(const TriangleMesh& mesh);

// Volume of the solid {p : winding(p) != 0}: the sum of the signed volumes of the shells that are
// a boundary of it (outermost shells, cavities), skipping same-orientation nested shells.
double solid_volume(const TriangleMesh& mesh);

// Winding number of `p` w.r.t. the listed triangles (all when empty), by counting signed crossings
// of the ray p + t e_x, t > 0, with symbolic perturbation so that rays through edges and vertices
// count exactly once on a closed mesh.
int winding_number(const TriangleMesh& mesh, const Vec3& p, const std::vector<int>& triangles = {});

// Where the line {(x, y, z) : x real} crosses triangle (a, b, c), if it does (with the same
// symbolic perturbation as winding_number: the line is taken at (y + eps, z + eps^2)). On a hit,
// `x` is the crossing and `sign` is +1 when the ray enters the solid (outward normal n_x < 0), -1
// when it leaves.
bool line_crossing_x(const Vec3& a, const Vec3& b, const Vec3& c, double y, double z, double* x,
                     int* sign);

struct Aabb {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
  Vec3 extent() const { return max - min; }
};
Aabb mesh_bounds(const TriangleMesh& mesh);

// Multiplies every vertex by `k` (metres per mesh unit). Throws InputError unless k > 0, finite,
// and the scaled coordinates stay within kMaxMeshCoordinate.
void scale_mesh(TriangleMesh& mesh, double k);
// The scale k that makes the largest bounding-box extent equal `size_m`.
double scale_for_size(const TriangleMesh& mesh, double size_m);

}  // namespace dentsim
