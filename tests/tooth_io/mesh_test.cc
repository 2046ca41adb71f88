// Mesh loading and validation (tooth_io/mesh.h): STL (binary, ASCII), OBJ with groups,
// welding, the error for each kind of broken mesh, divergence-theorem volume, nested shells,
// winding numbers through edges and vertices, scaling, and the two real meshes in ../shared/data.
#include "tooth_io/mesh.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

#include "reference/core/io.h"

namespace dentsim {
namespace {

using ::testing::HasSubstr;

// Unit cube [0,1]^3 as 12 outward triangles (each face split along a diagonal).
const char* kCubeObj = R"(
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

std::string stl_binary(const std::vector<std::array<Vec3, 3>>& tris) {
  std::string s(80, ' ');
  const auto n = static_cast<std::uint32_t>(tris.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : tris) {
    float f[12] = {0, 0, 0};
    for (int v = 0; v < 3; ++v) {
      for (int d = 0; d < 3; ++d) f[3 + 3 * v + d] = static_cast<float>(t[v][d]);
    }
    s.append(reinterpret_cast<const char*>(f), sizeof(f));
    s.append(2, '\0');
  }
  return s;
}

std::vector<std::array<Vec3, 3>> triangles_of(const TriangleMesh& m) {
  std::vector<std::array<Vec3, 3>> out;
  for (const auto& t : m.triangles) {
    out.push_back({m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]});
  }
  return out;
}

TriangleMesh cube() { return parse_obj(kCubeObj, "cube.obj").mesh; }

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no InputError>";
}

TEST(Mesh, ObjCubeQuadsAreFannedAndVolumeIsExact) {
  const LoadedMesh m = parse_obj(kCubeObj, "cube.obj");
  EXPECT_EQ(m.mesh.vertices.size(), 8u);
  EXPECT_EQ(m.mesh.triangles.size(), 12u);
  EXPECT_EQ(m.report.shells, 1);
  EXPECT_EQ(m.report.boundary_edges, 0);
  EXPECT_TRUE(m.report.repairs.empty());
  EXPECT_EQ(signed_volume(m.mesh), 1.0);
  EXPECT_EQ(solid_volume(m.mesh), 1.0);
}

TEST(Mesh, BinaryStlIsWeldedToEightVertices) {
  const std::string bytes = stl_binary(triangles_of(cube()));
  ASSERT_EQ(bytes.size(), 84u + 50u * 12u);
  const LoadedMesh m = parse_stl(bytes, "cube.stl");
  EXPECT_EQ(m.report.input_vertices, 36);
  EXPECT_EQ(m.report.welded_vertices, 28);
  EXPECT_EQ(m.mesh.vertices.size(), 8u);
  EXPECT_EQ(signed_volume(m.mesh), 1.0);
}

TEST(Mesh, BinaryStlWhoseHeaderSaysSolidIsBinary) {
  std::string bytes = stl_binary(triangles_of(cube()));
  bytes.replace(0, 12, "solid cube  ");  // many exporters write this
  const LoadedMesh m = parse_stl(bytes, "solid-header.stl");
  EXPECT_EQ(m.mesh.triangles.size(), 12u);
  EXPECT_EQ(signed_volume(m.mesh), 1.0);
}

TEST(Mesh, AsciiStlWithTwoSolidsGivesTwoGroups) {
  // A tetrahedron (volume 1/6) written as ASCII, followed by a second solid: a far tetrahedron.
  std::ostringstream s;
  auto solid = [&](const std::string& name, const Vec3& o) {
    const Vec3 p[4] = {o, o + Vec3(1, 0, 0), o + Vec3(0, 1, 0), o + Vec3(0, 0, 1)};
    const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    s << "solid " << name << "\n";
    for (const auto& t : f) {
      s << " facet normal 0 0 0\n  outer loop\n";
      for (int v : t) s << "   vertex " << p[v].x() << " " << p[v].y() << " " << p[v].z() << "\n";
      s << "  endloop\n endfacet\n";
    }
    s << "endsolid " << name << "\n";
  };
  solid("a", Vec3::Zero());
  solid("b", Vec3(5, 0, 0));
  const LoadedMesh m = parse_stl(s.str(), "tets.stl");
  EXPECT_THAT(m.mesh.groups, ::testing::ElementsAre("a", "b"));
  EXPECT_EQ(m.report.shells, 2);
  EXPECT_NEAR(signed_volume(m.mesh), 2.0 / 6.0, 1e-15);
  EXPECT_NEAR(solid_volume(m.mesh), 2.0 / 6.0, 1e-15);
}

TEST(Mesh, InsideOutCubeIsFlippedLoudly) {
  TriangleMesh c = cube();
  for (auto& t : c.triangles) std::swap(t[1], t[2]);
  const LoadedMesh m = parse_stl(stl_binary(triangles_of(c)), "inverted.stl");
  EXPECT_EQ(m.report.flipped_shells, 1);
  ASSERT_EQ(m.report.repairs.size(), 1u);
  EXPECT_THAT(m.report.repairs[0], HasSubstr("inside-out"));
  EXPECT_EQ(signed_volume(m.mesh), 1.0);
}

TEST(Mesh, BrokenMeshesAreRejectedWithEdgeCounts) {
  auto tris = triangles_of(cube());
  // Open: one triangle missing -> its three edges are boundary edges.
  auto open = tris;
  open.pop_back();
  EXPECT_THAT(message_of([&] { parse_stl(stl_binary(open), "open.stl"); }),
              HasSubstr("'open.stl': not a closed, consistently oriented manifold surface: 3 "
                        "boundary edges (holes), 0 edges shared by 3+ triangles, 0 edges"));
  // Non-manifold: a triangle duplicated -> its three edges are used three times.
  auto dup = tris;
  dup.push_back(tris[0]);
  EXPECT_THAT(message_of([&] { parse_stl(stl_binary(dup), "dup.stl"); }),
              HasSubstr("0 boundary edges (holes), 3 edges shared by 3+ triangles"));
  // Inconsistent: one triangle flipped.
  auto flip = tris;
  std::swap(flip[0][1], flip[0][2]);
  EXPECT_THAT(message_of([&] { parse_stl(stl_binary(flip), "flip.stl"); }),
              HasSubstr("3 edges with inconsistent winding"));
  // Empty.
  EXPECT_THAT(message_of([&] { parse_stl(stl_binary({}), "empty.stl"); }),
              HasSubstr("'empty.stl': no triangles"));
  // Truncated binary that does not start with "solid".
  std::string cut = stl_binary(tris);
  cut.resize(cut.size() - 7);
  EXPECT_THAT(message_of([&] { parse_stl(cut, "cut.stl"); }),
              HasSubstr("neither binary (size 84 + 50 * triangle count, here 677 bytes)"));
  // Non-finite coordinates.
  auto nan = tris;
  nan[3][1].x() = std::nan("");
  EXPECT_THAT(message_of([&] { parse_stl(stl_binary(nan), "nan.stl"); }),
              HasSubstr("triangle 3 vertex 1 is not finite"));
}

TEST(Mesh, DegenerateTrianglesAreRemovedLoudly) {
  auto tris = triangles_of(cube());
  tris.push_back({Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(0, 0, 0)});  // repeated vertex
  const LoadedMesh m = parse_stl(stl_binary(tris), "degen.stl");
  EXPECT_EQ(m.report.degenerate_triangles, 1);
  EXPECT_EQ(m.mesh.triangles.size(), 12u);
  ASSERT_EQ(m.report.repairs.size(), 1u);
  EXPECT_THAT(m.report.repairs[0], HasSubstr("removed 1 degenerate"));
}

TEST(Mesh, ObjErrorsNameTheLine) {
  EXPECT_THAT(message_of([] { parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 zz\n", "bad.obj"); }),
              HasSubstr("OBJ 'bad.obj' line 3: expected vertex z, found 'zz'"));
  EXPECT_THAT(message_of([] { parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "bad.obj"); }),
              HasSubstr("line 4: face vertex '7' is not a vertex index in 1..3"));
  EXPECT_THAT(message_of([] { parse_obj("v 0 0 0\nv 1 0 0\nf 1 2\n", "bad.obj"); }),
              HasSubstr("line 3: face has 2 vertices; expected 3 or more"));
  EXPECT_THAT(message_of([] { load_mesh("/nonexistent/tooth.off"); }),
              HasSubstr("unknown extension '.off'; expected .stl (binary or ASCII), .obj or .ply"));
  EXPECT_THAT(message_of([] { load_mesh("/nonexistent/tooth.stl"); }),
              HasSubstr("cannot read '/nonexistent/tooth.stl'"));
}

// Regressions from the fuzz targets (tests/fuzz/): errors quoted the input's raw bytes, so a
// crafted file could write control sequences to the user's terminal. They are escaped now.
bool has_control_byte(const std::string& s) {
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) return true;
  }
  return false;
}

TEST(Mesh, FuzzFoundRawBytesInMessagesAreEscaped) {
  // stl_fuzz: a control byte (0x1e) in place of the indentation of "endloop".
  const std::string stl =
      "solid t\n facet normal 0 0 0\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
      "   vertex 0 1 0\n\x1e endloop\n endfacet\nendsolid t\n";
  const std::string e1 = message_of([&] { parse_stl(stl, "f.stl"); });
  EXPECT_EQ(e1, "STL 'f.stl' line 7: unexpected keyword '\\x1e'");
  // obj_fuzz: a face index followed by 0xff bytes and 0x0e.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf -4\xff\xff\xff\x0e -4 -3 -1\n";
  const std::string e2 = message_of([&] { parse_obj(obj, "f.obj"); });
  EXPECT_EQ(e2, "OBJ 'f.obj' line 5: face vertex '-4\\xff\\xff\\xff\\x0e' is not a vertex index "
                "in 1..4 (or -1..-4)");
  EXPECT_FALSE(has_control_byte(e1));
  EXPECT_FALSE(has_control_byte(e2));
  const std::string e3 = message_of([] { parse_obj("v 0 0 \x1b[2J\n", "f.obj"); });
  EXPECT_EQ(e3, "OBJ 'f.obj' line 1: expected vertex z, found '\\x1b[2J'");
}

// A correctly oriented cube scaled to 1e300 used to come out "inside-out" with a negative volume
// (the triple products overflow); such coordinates are refused with the vertex named.
TEST(Mesh, HugeCoordinatesAreRefused) {
  // kCubeObj with every vertex coordinate 1 replaced by `side` (face lines untouched).
  auto cube_of_side = [](const std::string& side) {
    std::istringstream in(kCubeObj);
    std::string out, line;
    while (std::getline(in, line)) {
      if (line.rfind("v ", 0) == 0) {
        for (std::size_t at = 0; (at = line.find('1', at)) != std::string::npos;) {
          line.replace(at, 1, side);
          at += side.size();
        }
      }
      out += line + "\n";
    }
    return out;
  };
  EXPECT_EQ(message_of([&] { parse_obj(cube_of_side("1e300"), "big.obj"); }),
            "mesh 'big.obj': vertex 1 (1e+300      0      0) is too far out; expected "
            "|coordinate| <= 1000000000 mesh units (rescale the file)");
  // Up to the limit the volume is right and nothing is flipped: cube of side 1e9 -> 1e27.
  const LoadedMesh m = parse_obj(cube_of_side("1e9"), "edge.obj");
  EXPECT_EQ(m.report.flipped_shells, 0);
  EXPECT_DOUBLE_EQ(signed_volume(m.mesh), 1e27);
  // A scale that pushes a good mesh beyond the limit is refused too.
  TriangleMesh c = cube();
  EXPECT_THAT(message_of([&] { scale_mesh(c, 1e308); }), HasSubstr("the scaled mesh exceeds"));
}

TEST(Mesh, NonRegularFilesAreRefused) {
  // A mesh path that is /dev/zero or a FIFO used to fill memory or hang (issue #18).
  const auto tmp = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(::getpid());
  const std::string zero = (tmp / ("dentsim_mesh_zero_" + tag + ".stl")).string();
  const std::string fifo = (tmp / ("dentsim_mesh_fifo_" + tag + ".obj")).string();
  std::filesystem::create_symlink("/dev/zero", zero);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(message_of([&] { load_mesh(zero); }),
            "cannot read '" + zero + "': it is a character device; expected a regular file");
  EXPECT_EQ(message_of([&] { load_mesh(fifo); }),
            "cannot read '" + fifo + "': it is a FIFO; expected a regular file");
  std::filesystem::remove(zero);
  std::filesystem::remove(fifo);
}

// Cube [0,4]^3 (group "Tooth0") with a nested outward octahedron (group "Nerve"), a nested
// inward cube (a cavity) and negative / slash face indices.
std::string nested_obj(bool cavity) {
  std::ostringstream s;
  s << "g Tooth0\n";
  for (int k = 0; k < 2; ++k) {
    for (const auto& xy : {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(4, 4, 0), Vec3(0, 4, 0)}) {
      s << "v " << xy.x() << " " << xy.y() << " " << 4 * k << "\n";
    }
  }
  s << "f 1/1/1 4/1/1 3/1/1 2/1/1\nf 5//1 6//1 7//1 8//1\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\n"
       "f 4 1 5 8\n";
  s << "g Nerve\n";
  const Vec3 c(1.5, 1.5, 1.5);
  const Vec3 o[6] = {c + Vec3(1, 0, 0), c - Vec3(1, 0, 0), c + Vec3(0, 1, 0),
                     c - Vec3(0, 1, 0), c + Vec3(0, 0, 1), c - Vec3(0, 0, 1)};
  for (const Vec3& p : o) s << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
  // Octahedron faces, outward; vertices 9..14 addressed relative (-6..-1).
  const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (const auto& t : f) s << "f " << t[0] - 6 << " " << t[1] - 6 << " " << t[2] - 6 << "\n";
  if (cavity) {
    s << "g Void\n";
    const double a = 3.0, b = 3.5;  // cube [3, 3.5]^3, wound inward
    for (int k = 0; k < 2; ++k) {
      for (const auto& xy : {Vec3(a, a, 0), Vec3(b, a, 0), Vec3(b, b, 0), Vec3(a, b, 0)}) {
        s << "v " << xy.x() << " " << xy.y() << " " << (k ? b : a) << "\n";
      }
    }
    s << "f 15 16 17 18\nf 19 22 21 20\nf 15 19 20 16\nf 16 20 21 17\nf 17 21 22 18\n"
         "f 18 22 19 15\n";
  }
  return s.str();
}

TEST(Mesh, NestedShellIsMaterialCavityIsSubtracted) {
  const LoadedMesh m = parse_obj(nested_obj(false), "nested.obj");
  EXPECT_THAT(m.mesh.groups, ::testing::ElementsAre("", "Tooth0", "Nerve"));
  EXPECT_EQ(m.report.shells, 2);
  EXPECT_EQ(m.report.flipped_shells, 0);
  const double octahedron = 4.0 / 3.0;
  EXPECT_NEAR(signed_volume(m.mesh), 64.0 + octahedron, 1e-13);
  EXPECT_NEAR(solid_volume(m.mesh), 64.0, 1e-13);  // the Nerve is inside the tooth, not extra

  const LoadedMesh c = parse_obj(nested_obj(true), "cavity.obj");
  EXPECT_EQ(c.report.shells, 3);
  EXPECT_EQ(c.report.flipped_shells, 0);  // a nested inward shell is a cavity, not inside-out
  EXPECT_NEAR(solid_volume(c.mesh), 64.0 - 0.125, 1e-13);
  EXPECT_EQ(winding_number(c.mesh, Vec3(3.25, 3.25, 3.25)), 0);  // in the cavity
  EXPECT_EQ(winding_number(c.mesh, Vec3(1.5, 1.5, 1.5)), 2);     // in the nerve, in the tooth
  EXPECT_EQ(winding_number(c.mesh, Vec3(0.2, 3.9, 0.1)), 1);
}

// Rays through vertices and edges count once: the octahedron |x|+|y|+|z| <= 1 has vertices at
// (+-1, 0, 0) on the ray y = z = 0 and edges crossed by y = 0 or z = 0. Seed printed.
TEST(Mesh, WindingNumberIsExactThroughEdgesAndVertices) {
  const LoadedMesh m = parse_obj(nested_obj(false), "nested.obj");
  std::vector<int> nerve;
  for (int t = 0; t < static_cast<int>(m.mesh.triangles.size()); ++t) {
    if (m.mesh.groups[m.mesh.triangle_group[t]] == "Nerve") nerve.push_back(t);
  }
  ASSERT_EQ(nerve.size(), 8u);
  const unsigned seed = 20261121;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> grid(-5, 5);  // y, z on a lattice hitting edges and vertices
  std::uniform_real_distribution<double> ux(-2, 2);
  int checked = 0, through_edges = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 q(ux(rng), grid(rng) * 0.25, grid(rng) * 0.25);  // relative to the centre
    const double l1 = std::abs(q.x()) + std::abs(q.y()) + std::abs(q.z());
    if (std::abs(l1 - 1) < 1e-9) continue;  // on the surface
    const int expected = l1 < 1 ? 1 : 0;
    ASSERT_EQ(winding_number(m.mesh, Vec3(1.5, 1.5, 1.5) + q, nerve), expected)
        << "q = " << q.transpose();
    ++checked;
    if (q.y() == 0 || q.z() == 0 || std::abs(q.y()) + std::abs(q.z()) == 1) ++through_edges;
  }
  EXPECT_GT(checked, 19000);
  EXPECT_GT(through_edges, 5000);  // the degenerate cases are exercised
}

TEST(Mesh, ScaleAndTargetSize) {
  TriangleMesh c = cube();
  const double k = scale_for_size(c, 0.011);
  EXPECT_DOUBLE_EQ(k, 0.011);
  scale_mesh(c, 2.5e-3);
  EXPECT_DOUBLE_EQ(mesh_bounds(c).extent().maxCoeff(), 2.5e-3);
  EXPECT_NEAR(signed_volume(c), std::pow(2.5e-3, 3), 1e-22);
  EXPECT_THAT(message_of([&] { scale_mesh(c, -1); }), HasSubstr("expected a finite number > 0"));
  EXPECT_THAT(message_of([&] { scale_for_size(c, 0); }), HasSubstr("expected a finite number > 0"));
}

std::string shared_data(const std::string& file) {
  return std::string(DENTSIM_SOURCE_DIR) + "/../shared/data/" + file;
}

TEST(MeshRealData, MolarStlIsOneClosedShell) {
  const std::string path = shared_data("molar-cc0.stl");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "../shared/data absent: " << path;
  const LoadedMesh m = load_mesh(path);
  EXPECT_EQ(m.mesh.triangles.size(), 24576u);
  EXPECT_EQ(m.report.shells, 1);
  EXPECT_EQ(m.report.welded_vertices, 24576 * 3 - static_cast<int>(m.mesh.vertices.size()));
  EXPECT_TRUE(m.report.repairs.empty());
  const double v = solid_volume(m.mesh);
  std::printf("molar-cc0: %zu vertices, volume %.6f unit^3, extent %s\n", m.mesh.vertices.size(), v,
              (std::ostringstream() << mesh_bounds(m.mesh).extent().transpose()).str().c_str());
  EXPECT_GT(v, 0);
  EXPECT_DOUBLE_EQ(v, signed_volume(m.mesh));
}

TEST(MeshRealData, Chai3dToothHasNerveNestedInTooth) {
  const std::string path = shared_data("chai3d-tooth.obj");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "../shared/data absent: " << path;
  const LoadedMesh m = load_mesh(path);
  EXPECT_EQ(m.mesh.vertices.size(), 4384u);
  EXPECT_EQ(m.mesh.triangles.size(), 8768u);
  EXPECT_EQ(m.report.shells, 2);
  EXPECT_TRUE(m.report.repairs.empty());
  std::vector<int> tooth, nerve;
  for (int t = 0; t < static_cast<int>(m.mesh.triangles.size()); ++t) {
    const std::string& g = m.mesh.groups[m.mesh.triangle_group[t]];
    (g == "Nerve" ? nerve : tooth).push_back(t);
    if (g != "Nerve") {
      EXPECT_EQ(g, "Tooth0");
    }
  }
  EXPECT_EQ(nerve.size(), 5696u);
  EXPECT_EQ(tooth.size(), 3072u);
  const double v_tooth = signed_volume(m.mesh, tooth);
  const double v_nerve = signed_volume(m.mesh, nerve);
  std::printf("chai3d: tooth %.1f, nerve %.1f unit^3\n", v_tooth, v_nerve);
  EXPECT_GT(v_nerve, 0);
  EXPECT_DOUBLE_EQ(solid_volume(m.mesh), v_tooth);  // the nerve is a region of the solid
  const int nerve_vertex = m.mesh.triangles[nerve.front()][0];
  EXPECT_EQ(winding_number(m.mesh, m.mesh.vertices[nerve_vertex], tooth), 1);
}

}  // namespace
}  // namespace dentsim
