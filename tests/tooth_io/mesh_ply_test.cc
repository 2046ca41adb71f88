// PLY meshes (tooth_io/mesh_ply.h; issue #21): a UV sphere written as ASCII with per-vertex
// colour, binary little-endian with colour and normals, and binary big-endian with double
// coordinates and an extra element reads back as the same mesh; voxelised from a .ply file through
// load_mesh its volume is within 2 % of the sphere's (4/3 pi r^3) and within the discretisation
// bound of the mesh's own volume. Bad files get messages naming the file, the line or the element.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "reference/core/io.h"
#include "tests/support/input_error.h"
#include "tooth_io/mesh_ply.h"
#include "tooth_io/voxelize.h"

namespace dentsim {
namespace {

using ::testing::HasSubstr;

// A UV sphere of radius r: `seg` longitudes, `rings` latitudes; quads between rings (written as
// 4-gons), triangles at the poles, wound counter-clockwise seen from outside.
struct Poly {
  std::vector<Vec3> v;
  std::vector<std::vector<int>> f;
};
Poly uv_sphere(double r, int seg, int rings) {
  Poly p;
  p.v.push_back(Vec3(0, 0, -r));
  for (int i = 1; i < rings; ++i) {
    const double th = std::numbers::pi * i / rings;
    for (int j = 0; j < seg; ++j) {
      const double ph = 2 * std::numbers::pi * j / seg;
      p.v.push_back(r * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), -std::cos(th)));
    }
  }
  p.v.push_back(Vec3(0, 0, r));
  auto at = [seg](int ring, int j) { return 1 + (ring - 1) * seg + (j % seg); };
  const int top = static_cast<int>(p.v.size()) - 1;
  for (int j = 0; j < seg; ++j) p.f.push_back({0, at(1, j + 1), at(1, j)});
  for (int i = 1; i + 1 < rings; ++i) {
    for (int j = 0; j < seg; ++j) p.f.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
  }
  for (int j = 0; j < seg; ++j) p.f.push_back({at(rings - 1, j), at(rings - 1, j + 1), top});
  return p;
}

std::string header(const std::string& format, const Poly& p, const std::string& vertex_props,
                   const std::string& extra = "") {
  std::ostringstream h;
  h << "ply\nformat " << format << " 1.0\ncomment made by mesh_ply_test\nelement vertex "
    << p.v.size() << "\n" << vertex_props << "element face " << p.f.size()
    << "\nproperty list uchar int vertex_indices\n" << extra << "end_header\n";
  return h.str();
}

std::string ascii_ply(const Poly& p) {
  std::ostringstream o;
  o << header("ascii", p,
              "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
              "property uchar green\nproperty uchar blue\n");
  o.precision(17);  // the float values exactly, so all three encodings hold the same numbers
  for (const Vec3& v : p.v) {
    o << double(float(v.x())) << " " << double(float(v.y())) << " " << double(float(v.z()))
      << " 230 220 200\n";
  }
  for (const auto& f : p.f) {
    o << f.size();
    for (int i : f) o << " " << i;
    o << "\n";
  }
  return o.str();
}

template <typename T>
void put(std::string& s, T x, bool big) {
  char b[sizeof(T)];
  std::memcpy(b, &x, sizeof(T));
  if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

std::string binary_le_ply(const Poly& p) {
  std::string s = header("binary_little_endian", p,
                         "property float x\nproperty float y\nproperty float z\nproperty float nx\n"
                         "property float ny\nproperty float nz\nproperty uchar red\n"
                         "property uchar green\nproperty uchar blue\nproperty uchar alpha\n");
  for (const Vec3& v : p.v) {
    for (int d = 0; d < 3; ++d) put<float>(s, float(v[d]), false);
    for (int d = 0; d < 3; ++d) put<float>(s, float(v.normalized()[d]), false);
    for (int c = 0; c < 4; ++c) put<std::uint8_t>(s, 200, false);
  }
  for (const auto& f : p.f) {
    put<std::uint8_t>(s, static_cast<std::uint8_t>(f.size()), false);
    for (int i : f) put<std::int32_t>(s, i, false);
  }
  return s;
}

// Big-endian, double coordinates (rounded to float so all three files hold the same numbers),
// uint indices, and a trailing `edge` element that must be skipped.
std::string binary_be_ply(const Poly& p) {
  std::string s = header("binary_big_endian", p,
                         "property double x\nproperty double y\nproperty double z\n",
                         "element edge 2\nproperty int vertex1\nproperty int vertex2\n");
  // The header above declares face's list as uchar/int; rewrite it to uint for this file.
  s.replace(s.find("list uchar int"), 14, "list uchar uint");
  for (const Vec3& v : p.v) {
    for (int d = 0; d < 3; ++d) put<double>(s, double(float(v[d])), true);
  }
  for (const auto& f : p.f) {
    put<std::uint8_t>(s, static_cast<std::uint8_t>(f.size()), true);
    for (int i : f) put<std::uint32_t>(s, static_cast<std::uint32_t>(i), true);
  }
  for (int e = 0; e < 2; ++e) {
    put<std::int32_t>(s, e, true);
    put<std::int32_t>(s, e + 1, true);
  }
  return s;
}

TEST(MeshPly, ThreeEncodingsGiveOneMesh) {
  const Poly p = uv_sphere(1.0, 96, 48);
  const LoadedMesh a = parse_ply(ascii_ply(p), "a.ply");
  const LoadedMesh b = parse_ply(binary_le_ply(p), "b.ply");
  const LoadedMesh c = parse_ply(binary_be_ply(p), "c.ply");
  // Quads fanned: 2 triangles each; pole fans 1 each.
  const std::size_t triangles = 2 * 96 + 2 * 96 * 46;
  for (const LoadedMesh* m : {&a, &b, &c}) {
    EXPECT_EQ(m->mesh.vertices.size(), p.v.size());
    EXPECT_EQ(m->mesh.triangles.size(), triangles);
    EXPECT_EQ(m->report.shells, 1);
    EXPECT_TRUE(m->report.repairs.empty());
    EXPECT_EQ(m->mesh.vertices, a.mesh.vertices);
    EXPECT_EQ(m->mesh.triangles, a.mesh.triangles);
  }
  // The polyhedron's volume is below the sphere's by the chord deficit (< 0.3 % at 96 x 48).
  const double sphere = 4.0 / 3.0 * std::numbers::pi;
  EXPECT_LT(solid_volume(a.mesh), sphere);
  EXPECT_GT(solid_volume(a.mesh), 0.997 * sphere);
}

TEST(MeshPly, VoxelisedSphereWithinTwoPercent) {
  const auto dir = std::filesystem::temp_directory_path() / ("dentsim_ply_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "sphere.ply").string();
  write_file_atomic(file, binary_le_ply(uv_sphere(5.0, 96, 48)));  // 5 mm, unit mm
  LoadedMesh m = load_mesh(file);
  std::filesystem::remove_all(dir);
  scale_mesh(m.mesh, 1e-3);
  VoxelizeOptions opt;
  opt.resolution = 128;
  VoxelizeReport rep;
  const VoxelGrid g = voxelize_mesh(m.mesh, opt, &rep);
  const double voxels = rep.solid.solid_voxels() * g.voxel_volume();
  const double sphere = 4.0 / 3.0 * std::numbers::pi * 125e-9;
  std::printf("PLY sphere r = 5 mm at 128^3: %.3f mm^3 voxels, %.3f mesh, %.3f sphere\n",
              voxels * 1e9, solid_volume(m.mesh) * 1e9, sphere * 1e9);
  EXPECT_NEAR(voxels / sphere, 1.0, 0.02);
  EXPECT_LE(std::abs(voxels - solid_volume(m.mesh)), rep.solid.surface_voxels * g.voxel_volume());
}

TEST(MeshPly, BadFilesNameTheLineOrElement) {
  const Poly p = uv_sphere(1.0, 8, 4);
  EXPECT_THAT(testing::input_error_of([] { parse_ply("solid x\n", "x.ply"); }),
              HasSubstr("PLY 'x.ply' line 1: expected 'ply' as the first line"));
  EXPECT_THAT(testing::input_error_of([] { parse_ply("ply\nformat ascii 1.0\nelement vertex 3\n", "h.ply"); }),
              HasSubstr("PLY 'h.ply' line 3: the file ends in the header; expected 'end_header'"));
  EXPECT_THAT(testing::input_error_of([] { parse_ply("ply\nformat ascii 1.0\nbogus 1\nend_header\n", "k.ply"); }),
              HasSubstr("line 3: unknown header keyword 'bogus'"));
  EXPECT_THAT(testing::input_error_of([] { parse_ply("ply\nformat ascii 2.0\nend_header\n", "v.ply"); }),
              HasSubstr("line 2: format version '2.0'; expected 1.0"));
  EXPECT_THAT(testing::input_error_of([] {
                parse_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
                          "t.ply");
              }),
              HasSubstr("line 4: property type 'quad' is not a PLY type"));
  EXPECT_THAT(testing::input_error_of([] {
                parse_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n",
                          "n.ply");
              }),
              HasSubstr("element vertex lacks a scalar x, y or z property"));
  // Body errors.
  std::string ascii = ascii_ply(p);
  const std::string bad_number = std::string(ascii).replace(ascii.find("230"), 3, "2x0");
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(bad_number, "c.ply"); }),
              HasSubstr("PLY 'c.ply' vertex 0 (line 14): property 'red': expected a number, found '2x0'"));
  // The last face (31) is on line 13 + 26 vertices + 32 faces = 71.
  const std::string head = ascii.substr(0, ascii.rfind('\n', ascii.size() - 2) + 1);
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(head + "3 0 1 99\n", "i.ply"); }),
              HasSubstr("PLY 'i.ply' face 31 (line 71): vertex index 99 out of range 0..25"));
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(head + "2 0 1\n", "2.ply"); }),
              HasSubstr("face 31 (line 71): a face with 2 vertices; expected at least 3"));
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(head + "3 0 1 2 7\n", "x.ply"); }),
              HasSubstr("face 31 (line 71): unexpected '7' after the last property"));
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(head, "e.ply"); }),
              HasSubstr("face 31 of 32: the file ends; expected one line per face"));
  const std::string bin = binary_le_ply(p);
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(bin.substr(0, bin.size() - 3), "cut.ply"); }),
              HasSubstr("PLY 'cut.ply' face 31 of 32: the file ends in property 'vertex_indices'"));
  // A face with a missing neighbour: the surface is open (mesh.cc's validation, named).
  std::string open = head;
  open.replace(open.find("element face 32"), 15, "element face 31");
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(open, "o.ply"); }), HasSubstr("o.ply"));
  EXPECT_THAT(testing::input_error_of([&] { parse_ply(open, "o.ply"); }), HasSubstr("boundary edges"));
}

}  // namespace
}  // namespace dentsim
