// A triangle mesh as the tooth's geometry holds it: the type the mesh readers and the voxeliser
// (tooth_io/mesh.h, tooth_io/voxelize.h) produce and the sampled field (reference/tooth/
// sampled_field.h) measures distances to. Reading, validation and repair live in tooth_io/.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "reference/core/types.h"

namespace dentsim {

struct TriangleMesh {
  std::vector<Vec3> vertices;                 // mesh units, or [m] after scale_mesh()
  std::vector<std::array<int, 3>> triangles;  // vertex indices, CCW seen from outside
  std::vector<int> triangle_group;            // per triangle: index into `groups`
  std::vector<std::string> groups;            // group names (OBJ `g`/`o`); STL: one group ""
};

}  // namespace dentsim
