// PLY (Stanford polygon file) meshes from intraoral scanners (issue #21), beside STL and OBJ
// (mesh.h; load_mesh dispatches .ply here).
//
// Format (Turk, "The PLY polygon file format", 1994): a text header (`ply`, `format ascii 1.0 |
// binary_little_endian 1.0 | binary_big_endian 1.0`, `element NAME COUNT`, `property TYPE NAME`,
// `property list COUNT_TYPE ITEM_TYPE NAME`, `comment`/`obj_info`, `end_header`), then the
// elements in header order. Read: `vertex` x, y, z (any scalar type) and `face` vertex_indices
// (or vertex_index; polygons fanned into triangles as for OBJ). Every other property (per-vertex
// colour red/green/blue/alpha, normals, texture coordinates, quality) and every other element
// (edge, material, ...) is parsed and skipped: the tooth's materials come from its layers, not
// from surface colour. Units: none (as STL/OBJ: the caller scales, mesh.h).
//
// Errors (InputError) name the file and the header line, or the element and its index for the
// body ("face 12: vertex index 40 out of range 0..35"; "file ends in vertex 7 of 8").
#pragma once

#include <string>

#include "tooth_io/mesh.h"

namespace dentsim {

// Parses a PLY file's bytes, then welds, drops degenerate triangles and validates as parse_stl
// does (validate_and_repair). `name` names the file in errors.
LoadedMesh parse_ply(const std::string& bytes, const std::string& name);

}  // namespace dentsim
