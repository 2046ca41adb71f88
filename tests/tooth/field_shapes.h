// Shapes for the field tests (tests/tooth/sampled_field_test.cc, field_contact_test.cc,
// field_drilling_test.cc, tests/fast/field_test.cc).
#pragma once

#include "reference/core/types.h"
#include "reference/tooth/materials.h"
#include "reference/tooth/voxel_grid.h"
#include "tooth_io/mesh.h"

namespace dentsim::test {

// The axis-aligned box [lo, hi] rotated by R about `pivot`, as 12 outward triangles.
inline TriangleMesh box_mesh(const Vec3& lo, const Vec3& hi, const Mat3& R = Mat3::Identity(),
                             const Vec3& pivot = Vec3::Zero()) {
  TriangleMesh m;
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    m.vertices.push_back(pivot + R * (p - pivot));
  }
  const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                       {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  m.groups.push_back("");
  m.triangle_group.assign(m.triangles.size(), 0);
  return m;
}

// The n^3 grid of edge `side` at the origin whose voxels with their centre in `inside` are enamel.
template <class Inside>
VoxelGrid solid_grid(int n, double side, const Inside& inside) {
  VoxelGrid g(n, Vec3::Zero(), side / n);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (inside(g.center(i, j, k))) g.set(i, j, k, kEnamel);
      }
    }
  }
  return g;
}

}  // namespace dentsim::test
