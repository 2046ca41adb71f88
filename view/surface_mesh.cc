#include "view/surface_mesh.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace dentsim::view {
namespace {

constexpr int kW1[3] = {1, 2, 1};

}  // namespace

SurfaceMesher::SurfaceMesher(const VoxelGrid& grid, int block_size, CutAway cut)
    : SurfaceMesher(grid, nullptr, block_size, cut) {}

SurfaceMesher::SurfaceMesher(const VoxelGrid& grid, const SampledField* field, int block_size,
                             CutAway cut)
    : grid_(grid), block_size_(block_size), cut_(cut), field_(field) {
  if (block_size < 4) throw std::invalid_argument("SurfaceMesher: block size must be >= 4");
  if (field_ != nullptr) {
    if (field_->padding() < 1 || field_->samples_per_axis() < grid.n + 2 * field_->padding() ||
        std::abs(field_->voxel_size() - grid.voxel_size) > 1e-12 * grid.voxel_size) {
      throw std::invalid_argument("SurfaceMesher: the field is not the grid's");
    }
    iso_ = 0.0f;
    // edit_field_for_removed_voxels' radius R samples, plus the dual cells' reach.
    halo_ = field_->edit_radius() + 2;
  }
  nb_ = (grid.n + block_size - 1) / block_size;
  blocks_.resize(static_cast<std::size_t>(nb_) * nb_ * nb_);
  for (int b = 0; b < static_cast<int>(blocks_.size()); ++b) mesh_block(b);
}

bool SurfaceMesher::occupied(int i, int j, int k) const {
  if (!grid_.solid(i, j, k)) return false;
  return !(cut_.enabled && i >= cut_.i && j >= cut_.j);
}

void SurfaceMesher::set_cut(CutAway cut) {
  cut_ = cut;
  for (int b = 0; b < static_cast<int>(blocks_.size()); ++b) mesh_block(b);
}

std::size_t SurfaceMesher::triangle_count() const {
  std::size_t n = 0;
  for (const BlockMesh& b : blocks_) n += b.indices.size() / 3;
  return n;
}

std::vector<int> SurfaceMesher::blocks_touched_by(int i, int j, int k) const {
  std::vector<int> out;
  const int v[3] = {i, j, k};
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, (v[a] - halo_) / block_size_);
    if (v[a] - halo_ < 0) lo[a] = 0;
    hi[a] = std::min(nb_ - 1, (v[a] + halo_) / block_size_);
  }
  for (int bz = lo[2]; bz <= hi[2]; ++bz) {
    for (int by = lo[1]; by <= hi[1]; ++by) {
      for (int bx = lo[0]; bx <= hi[0]; ++bx) out.push_back(bx + nb_ * (by + nb_ * bz));
    }
  }
  return out;  // already sorted (z, y, x nesting matches the id order)
}

std::vector<int> SurfaceMesher::update(const VoxelGrid& grid,
                                       std::span<const std::size_t> changed) {
  if (grid.n != grid_.n) throw std::invalid_argument("SurfaceMesher::update: grid size changed");
  std::vector<int> dirty;
  const std::size_t n = static_cast<std::size_t>(grid_.n);
  for (std::size_t idx : changed) {
    if (idx >= grid_.voxels.size()) continue;
    grid_.voxels[idx] = grid.voxels[idx];
    const int i = static_cast<int>(idx % n), j = static_cast<int>((idx / n) % n),
              k = static_cast<int>(idx / (n * n));
    for (int b : blocks_touched_by(i, j, k)) dirty.push_back(b);
  }
  std::sort(dirty.begin(), dirty.end());
  dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
  for (int b : dirty) mesh_block(b);
  return dirty;
}

void SurfaceMesher::mesh_block(int block) {
  BlockMesh& out = blocks_[block];
  out.vertices.clear();
  out.indices.clear();
  ++out.version;
  const int B = block_size_;
  const int b0[3] = {(block % nb_) * B, ((block / nb_) % nb_) * B, (block / (nb_ * nb_)) * B};
  int b1[3];
  for (int a = 0; a < 3; ++a) b1[a] = std::min(grid_.n, b0[a] + B);
  // s over the block + 1 voxel halo: local index (c - b0 + 1).
  const int L = B + 2;
  s_.assign(static_cast<std::size_t>(L) * L * L, 0.0f);
  auto sidx = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i - b0[0] + 1) +
           static_cast<std::size_t>(L) * (static_cast<std::size_t>(j - b0[1] + 1) +
                                          static_cast<std::size_t>(L) * (k - b0[2] + 1));
  };
  const int pad = field_ != nullptr ? field_->padding() : 0;
  const float half_voxel = 0.5f * static_cast<float>(grid_.voxel_size);
  for (int k = b0[2] - 1; k <= b1[2]; ++k) {
    for (int j = b0[1] - 1; j <= b1[1]; ++j) {
      for (int i = b0[0] - 1; i <= b1[0]; ++i) {
        if (field_ != nullptr) {
          float s = -field_->at(i + pad, j + pad, k + pad);
          if (cut_.enabled && i >= cut_.i && j >= cut_.j) s = std::min(s, -half_voxel);
          s_[sidx(i, j, k)] = s;
          continue;
        }
        int sum = 0;
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              if (occupied(i + dx, j + dy, k + dz)) sum += kW1[dx + 1] * kW1[dy + 1] * kW1[dz + 1];
            }
          }
        }
        s_[sidx(i, j, k)] = static_cast<float>(sum) / 64.0f;
      }
    }
  }
  auto s_at = [&](int i, int j, int k) { return s_[sidx(i, j, k)]; };
  const float h = static_cast<float>(grid_.voxel_size);
  const Eigen::Vector3f origin = grid_.origin.cast<float>();

  // The vertex of dual cell c (corners c + {0,1}^3, all within the halo region).
  auto cell_vertex = [&](int ci, int cj, int ck, MeshVertex* v) {
    float corner[2][2][2];
    for (int z = 0; z < 2; ++z) {
      for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < 2; ++x) corner[z][y][x] = s_at(ci + x, cj + y, ck + z);
      }
    }
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    int count = 0;
    for (int a = 0; a < 3; ++a) {
      for (int u = 0; u < 2; ++u) {
        for (int w = 0; w < 2; ++w) {
          int p0[3], p1[3];
          p0[a] = 0;
          p1[a] = 1;
          p0[(a + 1) % 3] = p1[(a + 1) % 3] = u;
          p0[(a + 2) % 3] = p1[(a + 2) % 3] = w;
          const float s0 = corner[p0[2]][p0[1]][p0[0]], s1 = corner[p1[2]][p1[1]][p1[0]];
          if ((s0 >= iso_) == (s1 >= iso_)) continue;
          const float t = (iso_ - s0) / (s1 - s0);
          Eigen::Vector3f q(static_cast<float>(p0[0]), static_cast<float>(p0[1]),
                            static_cast<float>(p0[2]));
          q[a] += t;
          sum += q;
          ++count;
        }
      }
    }
    const Eigen::Vector3f local = sum / static_cast<float>(count);
    Eigen::Vector3f grad;
    grad.x() = (corner[0][0][1] + corner[0][1][1] + corner[1][0][1] + corner[1][1][1]) -
               (corner[0][0][0] + corner[0][1][0] + corner[1][0][0] + corner[1][1][0]);
    grad.y() = (corner[0][1][0] + corner[0][1][1] + corner[1][1][0] + corner[1][1][1]) -
               (corner[0][0][0] + corner[0][0][1] + corner[1][0][0] + corner[1][0][1]);
    grad.z() = (corner[1][0][0] + corner[1][0][1] + corner[1][1][0] + corner[1][1][1]) -
               (corner[0][0][0] + corner[0][0][1] + corner[0][1][0] + corner[0][1][1]);
    const float gn = grad.norm();
    const Eigen::Vector3f n = gn > 0.0f ? Eigen::Vector3f(-grad / gn) : Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f p =
        origin + h * (Eigen::Vector3f(static_cast<float>(ci), static_cast<float>(cj),
                                      static_cast<float>(ck)) +
                      local + Eigen::Vector3f::Constant(0.5f));
    for (int a = 0; a < 3; ++a) {
      v->p[a] = p[a];
      v->n[a] = n[a];
    }
  };

  auto material_of = [&](int i, int j, int k) -> float {
    if (occupied(i, j, k)) return grid_.at(i, j, k);
    std::array<int, kMaterialCount> count{};
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (occupied(i + dx, j + dy, k + dz)) ++count[grid_.at(i + dx, j + dy, k + dz)];
        }
      }
    }
    int best = 1;
    for (int m = 2; m < kMaterialCount; ++m) {
      if (count[m] > count[best]) best = m;
    }
    return static_cast<float>(best);
  };

  for (int k = b0[2]; k < b1[2]; ++k) {
    for (int j = b0[1]; j < b1[1]; ++j) {
      for (int i = b0[0]; i < b1[0]; ++i) {
        if (s_at(i, j, k) < iso_) continue;
        const int a_idx[3] = {i, j, k};
        float material = -1.0f;
        for (int axis = 0; axis < 3; ++axis) {
          for (int sign = -1; sign <= 1; sign += 2) {
            int nb[3] = {i, j, k};
            nb[axis] += sign;
            if (s_at(nb[0], nb[1], nb[2]) >= iso_) continue;
            if (material < 0.0f) material = material_of(i, j, k);
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            // Dual cells around the edge (a, a + sign e_axis): min corner along the axis is
            // min(a, a + sign e), across it a - {1, 0} in u and w; CCW seen from +axis.
            constexpr int du[4] = {-1, 0, 0, -1};
            constexpr int dw[4] = {-1, -1, 0, 0};
            const std::uint32_t base = static_cast<std::uint32_t>(out.vertices.size());
            for (int q = 0; q < 4; ++q) {
              int c[3];
              c[axis] = std::min(a_idx[axis], nb[axis]);
              c[u] = a_idx[u] + du[q];
              c[w] = a_idx[w] + dw[q];
              MeshVertex v;
              cell_vertex(c[0], c[1], c[2], &v);
              v.material = material;
              out.vertices.push_back(v);
            }
            if (sign > 0) {
              out.indices.insert(out.indices.end(),
                                 {base, base + 1, base + 2, base, base + 2, base + 3});
            } else {
              out.indices.insert(out.indices.end(),
                                 {base, base + 2, base + 1, base, base + 3, base + 2});
            }
          }
        }
      }
    }
  }
}

CutAway centre_cut(const VoxelGrid& grid) {
  int lo[2] = {grid.n, grid.n}, hi[2] = {-1, -1};
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        lo[0] = std::min(lo[0], i);
        hi[0] = std::max(hi[0], i);
        lo[1] = std::min(lo[1], j);
        hi[1] = std::max(hi[1], j);
      }
    }
  }
  CutAway c;
  if (hi[0] < 0) return c;
  c.enabled = true;
  c.i = (lo[0] + hi[0] + 1) / 2;
  c.j = (lo[1] + hi[1] + 1) / 2;
  return c;
}

}  // namespace dentsim::view
