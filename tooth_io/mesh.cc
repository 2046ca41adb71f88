#include "tooth_io/mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "reference/core/io.h"
#include "tooth_io/mesh_ply.h"

namespace dentsim {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

// Sign of the edge function of the directed edge u -> v at the point (y, z) in the yz-plane,
// symbolically perturbed to (y + eps, z + eps^2). Computed on the canonically ordered endpoints
// and negated for the reverse direction, so the two triangles sharing an edge see exactly opposite
// signs (a ray through the edge counts once).
int edge_sign(const Vec3& u, const Vec3& v, double y, double z, double* value) {
  const bool swap = (v.y() < u.y()) || (v.y() == u.y() && v.z() < u.z());
  const Vec3& p = swap ? v : u;
  const Vec3& q = swap ? u : v;
  const double dy = q.y() - p.y();
  const double dz = q.z() - p.z();
  double e = dy * (z - p.z()) - dz * (y - p.y());
  int s;
  if (e > 0) {
    s = 1;
  } else if (e < 0) {
    s = -1;
  } else if (dz != 0) {
    s = dz < 0 ? 1 : -1;  // e(eps) = -dz eps + dy eps^2
  } else {
    s = dy > 0 ? 1 : (dy < 0 ? -1 : 0);
  }
  if (swap) {
    s = -s;
    e = -e;
  }
  *value = e;
  return s;
}

struct Edge {
  int count = 0;
  int net = 0;  // +1 per use min -> max, -1 per use max -> min
};

std::unordered_map<std::uint64_t, Edge> edge_map(const TriangleMesh& mesh) {
  std::unordered_map<std::uint64_t, Edge> edges;
  edges.reserve(mesh.triangles.size() * 2);
  for (const auto& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) {
      const int a = t[e], b = t[(e + 1) % 3];
      const auto lo = static_cast<std::uint64_t>(std::min(a, b));
      const auto hi = static_cast<std::uint64_t>(std::max(a, b));
      Edge& ed = edges[(lo << 32) | hi];
      ++ed.count;
      ed.net += a < b ? 1 : -1;
    }
  }
  return edges;
}

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Sum of the windings of every shell but `self` at a vertex of shell `self`.
int winding_outside_shell(const TriangleMesh& mesh, const std::vector<std::vector<int>>& shells,
                          std::size_t self) {
  const Vec3& p = mesh.vertices[mesh.triangles[shells[self].front()][0]];
  int w = 0;
  for (std::size_t s = 0; s < shells.size(); ++s) {
    if (s != self) w += winding_number(mesh, p, shells[s]);
  }
  return w;
}

void append_triangle(TriangleMesh& mesh, const std::array<int, 3>& t, int group) {
  mesh.triangles.push_back(t);
  mesh.triangle_group.push_back(group);
}

double parse_number(std::istringstream& in, const std::string& where, const char* what) {
  std::string tok;
  if (!(in >> tok)) throw InputError(where + ": expected " + what + ", found end of line");
  char* end = nullptr;
  const double v = std::strtod(tok.c_str(), &end);
  if (end == tok.c_str() || *end != '\0') {
    throw InputError(where + ": expected " + what + ", found '" + printable(tok) + "'");
  }
  if (!std::isfinite(v)) {
    throw InputError(where + ": " + what + " is not finite ('" + printable(tok) + "')");
  }
  return v;
}

LoadedMesh finish(TriangleMesh mesh, const std::string& name) {
  LoadedMesh out;
  out.report = validate_and_repair(mesh, name);
  out.mesh = std::move(mesh);
  return out;
}

LoadedMesh parse_stl_binary(const std::string& bytes, const std::string& name) {
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  TriangleMesh mesh;
  mesh.groups.push_back("");
  mesh.vertices.reserve(static_cast<std::size_t>(n) * 3);
  for (std::uint32_t t = 0; t < n; ++t) {
    const char* rec = bytes.data() + 84 + static_cast<std::size_t>(t) * 50;
    float f[12];
    std::memcpy(f, rec, sizeof(f));
    std::array<int, 3> tri{};
    for (int v = 0; v < 3; ++v) {
      const Vec3 p(f[3 + 3 * v], f[4 + 3 * v], f[5 + 3 * v]);
      if (!p.allFinite()) {
        throw InputError("STL '" + name + "': triangle " + std::to_string(t) + " vertex " +
                         std::to_string(v) + " is not finite (NaN or inf); expected finite floats");
      }
      tri[v] = static_cast<int>(mesh.vertices.size());
      mesh.vertices.push_back(p);
    }
    append_triangle(mesh, tri, 0);
  }
  return finish(std::move(mesh), name);
}

LoadedMesh parse_stl_ascii(const std::string& text, const std::string& name) {
  TriangleMesh mesh;
  std::istringstream lines(text);
  std::string line;
  int line_no = 0;
  int group = -1;
  std::vector<int> loop;
  bool in_loop = false;
  while (std::getline(lines, line)) {
    ++line_no;
    const std::string where = "STL '" + name + "' line " + std::to_string(line_no);
    std::istringstream in(line);
    std::string key;
    if (!(in >> key)) continue;
    key = lower(key);
    if (key == "solid") {
      std::string rest;
      std::getline(in, rest);
      mesh.groups.push_back(trim(rest));
      group = static_cast<int>(mesh.groups.size()) - 1;
    } else if (key == "outer") {
      if (group < 0) throw InputError(where + ": 'outer loop' before 'solid'");
      in_loop = true;
      loop.clear();
    } else if (key == "vertex") {
      if (!in_loop) throw InputError(where + ": 'vertex' outside 'outer loop'");
      const double x = parse_number(in, where, "vertex x");
      const double y = parse_number(in, where, "vertex y");
      const double z = parse_number(in, where, "vertex z");
      loop.push_back(static_cast<int>(mesh.vertices.size()));
      mesh.vertices.emplace_back(x, y, z);
    } else if (key == "endloop") {
      if (loop.size() != 3) {
        throw InputError(where + ": facet has " + std::to_string(loop.size()) +
                         " vertices; expected 3");
      }
      append_triangle(mesh, {loop[0], loop[1], loop[2]}, group);
      in_loop = false;
    } else if (key != "facet" && key != "endfacet" && key != "endsolid") {
      throw InputError(where + ": unexpected keyword '" + printable(key) + "'");
    }
  }
  if (in_loop) throw InputError("STL '" + name + "': file ends inside a facet");
  return finish(std::move(mesh), name);
}

}  // namespace

bool line_crossing_x(const Vec3& a, const Vec3& b, const Vec3& c, double y, double z, double* x,
                     int* sign) {
  double eab, ebc, eca;
  const int sab = edge_sign(a, b, y, z, &eab);
  const int sbc = edge_sign(b, c, y, z, &ebc);
  const int sca = edge_sign(c, a, y, z, &eca);
  if (sab == 0 || sab != sbc || sab != sca) return false;
  // Barycentric weights of a, b, c are the edge functions of the opposite edges.
  const double wsum = eab + ebc + eca;
  *x = wsum != 0 ? (ebc * a.x() + eca * b.x() + eab * c.x()) / wsum : (a.x() + b.x() + c.x()) / 3;
  // Positive edge functions <=> n_x = ((b - a) x (c - a))_x > 0 <=> the ray along +x leaves.
  *sign = sab > 0 ? -1 : 1;
  return true;
}

int winding_number(const TriangleMesh& mesh, const Vec3& p, const std::vector<int>& triangles) {
  int w = 0;
  auto visit = [&](int t) {
    const auto& tri = mesh.triangles[t];
    double x;
    int s;
    if (line_crossing_x(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]], p.y(),
                        p.z(), &x, &s) &&
        x > p.x()) {
      w -= s;  // the ray from p to +infinity: leaving (-1) means p was inside
    }
  };
  if (triangles.empty()) {
    for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) visit(t);
  } else {
    for (int t : triangles) visit(t);
  }
  return w;
}

double signed_volume(const TriangleMesh& mesh, const std::vector<int>& triangles) {
  double v = 0;
  auto add = [&](int t) {
    const auto& tri = mesh.triangles[t];
    const Vec3& a = mesh.vertices[tri[0]];
    v += a.dot(mesh.vertices[tri[1]].cross(mesh.vertices[tri[2]]));
  };
  if (triangles.empty()) {
    for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) add(t);
  } else {
    for (int t : triangles) add(t);
  }
  return v / 6.0;
}

std::vector<std::vector<int>> mesh_shells(const TriangleMesh& mesh) {
  std::vector<int> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : mesh.triangles) {
    const int r0 = find_root(parent, t[0]);
    const int r1 = find_root(parent, t[1]);
    const int r2 = find_root(parent, t[2]);
    parent[r1] = r0;
    parent[find_root(parent, r2)] = r0;
  }
  std::unordered_map<int, std::size_t> shell_of_root;
  std::vector<std::vector<int>> shells;
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
    const int r = find_root(parent, mesh.triangles[t][0]);
    auto [it, inserted] = shell_of_root.emplace(r, shells.size());
    if (inserted) shells.emplace_back();
    shells[it->second].push_back(t);
  }
  return shells;
}

double solid_volume(const TriangleMesh& mesh) {
  const auto shells = mesh_shells(mesh);
  double v = 0;
  for (std::size_t s = 0; s < shells.size(); ++s) {
    const double vs = signed_volume(mesh, shells[s]);
    const int w_out = winding_outside_shell(mesh, shells, s);
    const int w_in = w_out + (vs > 0 ? 1 : -1);
    if ((w_out != 0) != (w_in != 0)) v += vs;  // the shell bounds the solid
  }
  return v;
}

MeshReport validate_and_repair(TriangleMesh& mesh, const std::string& name) {
  MeshReport r;
  r.input_vertices = static_cast<int>(mesh.vertices.size());
  r.input_triangles = static_cast<int>(mesh.triangles.size());
  const std::string what = "mesh '" + name + "'";
  if (mesh.triangles.empty()) throw InputError(what + ": no triangles; expected a closed surface");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      throw InputError(what + ": vertex " + std::to_string(i) + " is not finite");
    }
    // Bounded so that volumes (products of three coordinates) and winding tests stay finite.
    if (mesh.vertices[i].cwiseAbs().maxCoeff() > kMaxMeshCoordinate) {
      std::ostringstream v;
      v << mesh.vertices[i].transpose();
      throw InputError(what + ": vertex " + std::to_string(i) + " (" + v.str() +
                       ") is too far out; expected |coordinate| <= " +
                       std::to_string(static_cast<long long>(kMaxMeshCoordinate)) +
                       " mesh units (rescale the file)");
    }
  }

  // Weld exact duplicates (-0 and +0 are one position).
  struct Key {
    std::uint64_t c[3];
    bool operator==(const Key& o) const {
      return c[0] == o.c[0] && c[1] == o.c[1] && c[2] == o.c[2];
    }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      return std::hash<std::uint64_t>()(k.c[0] * 0x9E3779B97F4A7C15ull ^ (k.c[1] << 1) ^
                                        (k.c[2] * 0xC2B2AE3D27D4EB4Full));
    }
  };
  std::unordered_map<Key, int, KeyHash> index_of;
  index_of.reserve(mesh.vertices.size());
  std::vector<int> remap(mesh.vertices.size());
  std::vector<Vec3> welded;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    Key k;
    for (int d = 0; d < 3; ++d) k.c[d] = std::bit_cast<std::uint64_t>(mesh.vertices[i][d] + 0.0);
    auto [it, inserted] = index_of.emplace(k, static_cast<int>(welded.size()));
    if (inserted) welded.push_back(mesh.vertices[i]);
    remap[i] = it->second;
  }
  r.welded_vertices = static_cast<int>(mesh.vertices.size() - welded.size());
  mesh.vertices = std::move(welded);

  // Drop triangles with a repeated vertex (their edges cancel: removal keeps the surface closed).
  std::vector<std::array<int, 3>> tris;
  std::vector<int> groups;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::array<int, 3> tri{};
    for (int v = 0; v < 3; ++v) {
      const int idx = mesh.triangles[t][v];
      if (idx < 0 || idx >= static_cast<int>(remap.size())) {
        throw InputError(what + ": triangle " + std::to_string(t) + " refers to vertex " +
                         std::to_string(idx) + "; expected 0.." + std::to_string(remap.size() - 1));
      }
      tri[v] = remap[idx];
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) {
      ++r.degenerate_triangles;
      continue;
    }
    tris.push_back(tri);
    groups.push_back(mesh.triangle_group[t]);
  }
  mesh.triangles = std::move(tris);
  mesh.triangle_group = std::move(groups);
  if (r.degenerate_triangles > 0) {
    r.repairs.push_back("removed " + std::to_string(r.degenerate_triangles) +
                        " degenerate triangles (a vertex repeated after welding)");
  }
  if (mesh.triangles.empty()) {
    throw InputError(what + ": every triangle is degenerate; expected a closed surface");
  }

  for (const auto& [key, e] : edge_map(mesh)) {
    if (e.count == 1) {
      ++r.boundary_edges;
    } else if (e.count > 2) {
      ++r.nonmanifold_edges;
    } else if (e.net != 0) {
      ++r.inconsistent_edges;
    }
  }
  if (r.boundary_edges > 0 || r.nonmanifold_edges > 0 || r.inconsistent_edges > 0) {
    throw InputError(what + ": not a closed, consistently oriented manifold surface: " +
                     std::to_string(r.boundary_edges) + " boundary edges (holes), " +
                     std::to_string(r.nonmanifold_edges) + " edges shared by 3+ triangles, " +
                     std::to_string(r.inconsistent_edges) +
                     " edges with inconsistent winding; expected every edge shared by exactly "
                     "two triangles in opposite directions");
  }

  // Turn inside-out outermost shells outward (safe: the shell is closed and consistent).
  const auto shells = mesh_shells(mesh);
  r.shells = static_cast<int>(shells.size());
  for (std::size_t s = 0; s < shells.size(); ++s) {
    if (signed_volume(mesh, shells[s]) >= 0) continue;
    if (winding_outside_shell(mesh, shells, s) != 0) continue;  // a cavity: inward is right
    for (int t : shells[s]) std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
    ++r.flipped_shells;
    r.repairs.push_back("shell " + std::to_string(s) + " (" + std::to_string(shells[s].size()) +
                        " triangles) was inside-out (negative volume): flipped outward");
  }
  return r;
}

LoadedMesh parse_stl(const std::string& bytes, const std::string& name) {
  std::size_t i = 0;
  while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
  const bool starts_solid = lower(bytes.substr(i, 5)) == "solid";
  // Binary headers may also start with "solid": ASCII needs a "facet" keyword early on too.
  if (starts_solid && lower(bytes.substr(0, 1024)).find("facet") != std::string::npos) {
    return parse_stl_ascii(bytes, name);
  }
  if (bytes.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50 * static_cast<std::uint64_t>(n)) {
      return parse_stl_binary(bytes, name);
    }
  }
  if (starts_solid) return parse_stl_ascii(bytes, name);
  throw InputError("STL '" + name + "': neither binary (size 84 + 50 * triangle count, here " +
                   std::to_string(bytes.size()) + " bytes) nor ASCII (starting with 'solid')");
}

LoadedMesh parse_obj(const std::string& text, const std::string& name) {
  TriangleMesh mesh;
  mesh.groups.push_back("");
  int group = 0;
  std::istringstream lines(text);
  std::string line;
  int line_no = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    const std::string where = "OBJ '" + name + "' line " + std::to_string(line_no);
    std::istringstream in(line);
    std::string key;
    if (!(in >> key) || key[0] == '#') continue;
    if (key == "v") {
      const double x = parse_number(in, where, "vertex x");
      const double y = parse_number(in, where, "vertex y");
      const double z = parse_number(in, where, "vertex z");
      mesh.vertices.emplace_back(x, y, z);
    } else if (key == "f") {
      std::vector<int> poly;
      std::string tok;
      while (in >> tok) {
        const std::string idx = tok.substr(0, tok.find('/'));
        char* end = nullptr;
        const long v = std::strtol(idx.c_str(), &end, 10);
        const long nv = static_cast<long>(mesh.vertices.size());
        const long resolved = v > 0 ? v - 1 : nv + v;  // negative indices count back
        if (idx.empty() || *end != '\0' || v == 0 || resolved < 0 || resolved >= nv) {
          throw InputError(where + ": face vertex '" + printable(tok) +
                           "' is not a vertex index in 1.." + std::to_string(nv) + " (or -1..-" +
                           std::to_string(nv) + ")");
        }
        poly.push_back(static_cast<int>(resolved));
      }
      if (poly.size() < 3) {
        throw InputError(where + ": face has " + std::to_string(poly.size()) +
                         " vertices; expected 3 or more");
      }
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) {  // fan
        append_triangle(mesh, {poly[0], poly[k], poly[k + 1]}, group);
      }
    } else if (key == "g" || key == "o") {
      std::string rest;
      std::getline(in, rest);
      const std::string g = trim(rest);
      auto it = std::find(mesh.groups.begin(), mesh.groups.end(), g);
      group = static_cast<int>(it - mesh.groups.begin());
      if (it == mesh.groups.end()) mesh.groups.push_back(g);
    }
    // vn, vt, usemtl, mtllib, s, l, p: not needed for the solid; ignored.
  }
  return finish(std::move(mesh), name);
}

LoadedMesh load_mesh(const std::string& path) {
  const std::string ext = lower(path.substr(
      path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.')));
  if (ext == ".stl") return parse_stl(read_file(path), path);
  if (ext == ".obj") return parse_obj(read_file(path), path);
  if (ext == ".ply") return parse_ply(read_file(path), path);
  throw InputError("mesh '" + path + "': unknown extension '" + ext +
                   "'; expected .stl (binary or ASCII), .obj or .ply");
}

Aabb mesh_bounds(const TriangleMesh& mesh) {
  Aabb b;
  if (mesh.vertices.empty()) return b;
  b.min = b.max = mesh.vertices.front();
  for (const Vec3& v : mesh.vertices) {
    b.min = b.min.cwiseMin(v);
    b.max = b.max.cwiseMax(v);
  }
  return b;
}

void scale_mesh(TriangleMesh& mesh, double k) {
  if (!(k > 0) || !std::isfinite(k)) {
    throw InputError("mesh scale " + std::to_string(k) + ": expected a finite number > 0");
  }
  for (Vec3& v : mesh.vertices) v *= k;
  const Aabb box = mesh_bounds(mesh);
  if (!(std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()) <=
        kMaxMeshCoordinate)) {
    throw InputError("mesh scale " + std::to_string(k) + ": the scaled mesh exceeds " +
                     std::to_string(static_cast<long long>(kMaxMeshCoordinate)) +
                     " m; expected a scale that makes a tooth-sized mesh");
  }
}

double scale_for_size(const TriangleMesh& mesh, double size_m) {
  if (!(size_m > 0) || !std::isfinite(size_m)) {
    throw InputError("target size " + std::to_string(size_m) + " m: expected a finite number > 0");
  }
  const double extent = mesh_bounds(mesh).extent().maxCoeff();
  if (!(extent > 0)) throw InputError("mesh has zero extent; cannot scale it to a size");
  return size_m / extent;
}

}  // namespace dentsim
