#include "view/surface_mesh.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "reference/core/setup_threads.h"
#include "view/field_values.h"

namespace dentsim::view {

SurfaceMesher::SurfaceMesher(const VoxelGrid& grid, int block_size, CutAway cut)
    : SurfaceMesher(grid, nullptr, block_size, cut) {}

SurfaceMesher::SurfaceMesher(const VoxelGrid& grid, const SampledField* field, int block_size,
                             CutAway cut)
    : SurfaceMesher(nullptr, grid, field, block_size, cut, 1) {}

SurfaceMesher SurfaceMesher::borrowing(const VoxelGrid& grid, const SampledField* field,
                                       int block_size, CutAway cut, int threads) {
  return SurfaceMesher(&grid, grid, field, block_size, cut,
                       threads > 0 ? threads : setup_threads());
}

SurfaceMesher::SurfaceMesher(const VoxelGrid* borrowed, const VoxelGrid& grid,
                             const SampledField* field, int block_size, CutAway cut, int threads)
    : own_(borrowed == nullptr ? grid : VoxelGrid()),
      borrowed_(borrowed),
      block_size_(block_size),
      cut_(cut),
      field_(field),
      threads_(threads) {
  if (block_size < 4) throw std::invalid_argument("SurfaceMesher: block size must be >= 4");
  if (field_ != nullptr) {
    const int k = field_->stride();
    if (field_->padding() < 1 || k < 1 ||
        field_->samples_per_axis() < (grid.n - 1) / k + 1 + 2 * field_->padding() ||
        std::abs(field_->voxel_size() - grid.voxel_size) > 1e-12 * grid.voxel_size) {
      throw std::invalid_argument("SurfaceMesher: the field is not the grid's");
    }
    iso_ = 0.0f;
    // edit_field_for_removed_voxels' radius R_v voxels, the k - 1 voxels over which a sample's
    // cells reach the voxel centres read by interpolation (stride k > 1), and the dual cells'
    // reach (2). At k = 1: R + 2.
    halo_ = field_->edit_radius_voxels() + (k - 1) + 2;
  }
  nb_ = (grid.n + block_size - 1) / block_size;
  blocks_.resize(static_cast<std::size_t>(nb_) * nb_ * nb_);
  if (field_ == nullptr) count_block_solids();
  mesh_all();
}

void SurfaceMesher::mesh_all() {
  // Tasks of a row of blocks (x): each block is meshed by one task into its own BlockMesh from
  // the grid and field, which no task writes, so the blocks are the one-thread ones.
  const int rows = nb_ * nb_;
  parallel_tasks(rows, threads_, [&](int row) {
    Scratch scratch;
    for (int b = row * nb_; b < (row + 1) * nb_; ++b) mesh_block(b, scratch);
  });
}

bool SurfaceMesher::occupied(int i, int j, int k) const {
  if (!grid().solid(i, j, k)) return false;
  return !(cut_.enabled && i >= cut_.i && j >= cut_.j);
}

void SurfaceMesher::set_cut(CutAway cut) {
  cut_ = cut;
  mesh_all();
}

std::size_t SurfaceMesher::triangle_count() const {
  std::size_t n = 0;
  for (const BlockMesh& b : blocks_) n += b.indices.size() / 3;
  return n;
}

void SurfaceMesher::append_blocks(const int lo[3], const int hi[3], std::vector<int>* out) const {
  int blo[3], bhi[3];
  for (int a = 0; a < 3; ++a) {
    if (hi[a] < 0 || lo[a] >= grid().n) return;  // the box misses the grid
    blo[a] = std::max(0, lo[a]) / block_size_;
    bhi[a] = std::min(nb_ - 1, hi[a] / block_size_);
  }
  for (int bz = blo[2]; bz <= bhi[2]; ++bz) {
    for (int by = blo[1]; by <= bhi[1]; ++by) {
      for (int bx = blo[0]; bx <= bhi[0]; ++bx) out->push_back(bx + nb_ * (by + nb_ * bz));
    }
  }
}

std::vector<int> SurfaceMesher::blocks_touched_by(int i, int j, int k) const {
  std::vector<int> out;
  const int lo[3] = {i - halo_, j - halo_, k - halo_}, hi[3] = {i + halo_, j + halo_, k + halo_};
  append_blocks(lo, hi, &out);
  return out;  // already sorted (z, y, x nesting matches the id order)
}

void SurfaceMesher::copy_voxels(const VoxelGrid& grid, std::span<const std::size_t> changed) {
  if (borrowed_ != nullptr) {
    throw std::logic_error("SurfaceMesher::update: a borrowing mesher (borrowing()) has no copy "
                           "of the grid to update");
  }
  if (grid.n != own_.n) throw std::invalid_argument("SurfaceMesher::update: grid size changed");
  const std::size_t n = static_cast<std::size_t>(own_.n);
  const std::size_t B = static_cast<std::size_t>(block_size_), nb = static_cast<std::size_t>(nb_);
  for (std::size_t idx : changed) {
    if (idx >= own_.voxels.size()) continue;
    const bool was_solid = own_.voxels[idx] != 0;
    own_.voxels[idx] = grid.voxels[idx];
    if (!block_solid_.empty() && was_solid != (own_.voxels[idx] != 0)) {
      const std::size_t b = (idx % n) / B + nb * (((idx / n) % n) / B + nb * ((idx / (n * n)) / B));
      block_solid_[b] = was_solid ? block_solid_[b] - 1 : block_solid_[b] + 1;
    }
  }
}

std::vector<int> SurfaceMesher::remesh(std::vector<int> dirty) {
  std::sort(dirty.begin(), dirty.end());
  dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
  for (int b : dirty) mesh_block(b, scratch_);
  return dirty;
}

std::vector<int> SurfaceMesher::update(const VoxelGrid& grid,
                                       std::span<const std::size_t> changed) {
  return update_voxels(grid, changed, halo_, {});
}

std::vector<int> SurfaceMesher::update(const VoxelGrid& grid, std::span<const std::size_t> changed,
                                       std::span<const std::array<int, 3>> samples) {
  if (field_ == nullptr) {
    throw std::logic_error("SurfaceMesher::update: changed samples given to a mesher of voxels");
  }
  return update_voxels(grid, changed, kHalo, samples);
}

std::vector<int> SurfaceMesher::update_voxels(const VoxelGrid& grid,
                                              std::span<const std::size_t> changed, int halo,
                                              std::span<const std::array<int, 3>> samples) {
  copy_voxels(grid, changed);
  std::vector<int> dirty;
  const std::size_t n = static_cast<std::size_t>(own_.n);
  for (std::size_t idx : changed) {
    if (idx >= own_.voxels.size()) continue;
    const int v[3] = {static_cast<int>(idx % n), static_cast<int>((idx / n) % n),
                      static_cast<int>(idx / (n * n))};
    const int lo[3] = {v[0] - halo, v[1] - halo, v[2] - halo};
    const int hi[3] = {v[0] + halo, v[1] + halo, v[2] + halo};
    append_blocks(lo, hi, &dirty);
  }
  const int k = field_ != nullptr ? field_->stride() : 1;
  const int pad = field_ != nullptr ? field_->padding() : 0;
  for (const std::array<int, 3>& s : samples) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      // The centres whose value reads sample s (header), widened by the dual cells' reach of 1.
      lo[a] = (k == 1 ? s[a] - pad : k * (s[a] - pad - 1)) - 1;
      hi[a] = (k == 1 ? s[a] - pad : k * (s[a] - pad) + k - 1) + 1;
    }
    append_blocks(lo, hi, &dirty);
  }
  return remesh(std::move(dirty));
}

void SurfaceMesher::count_block_solids() {
  block_solid_.assign(blocks_.size(), 0);
  const std::size_t n = static_cast<std::size_t>(grid().n);
  const int B = block_size_;
  for (int k = 0; k < grid().n; ++k) {
    for (int j = 0; j < grid().n; ++j) {
      const std::uint8_t* row = grid().voxels.data() + n * (static_cast<std::size_t>(j) + n * k);
      const std::size_t base = static_cast<std::size_t>(nb_) * (j / B + nb_ * (k / B));
      for (int i = 0; i < grid().n; ++i) block_solid_[base + i / B] += row[i] != 0 ? 1 : 0;
    }
  }
}

bool SurfaceMesher::uniform_neighbourhood(const int b0[3]) const {
  // A block's quads read o within +-2 voxels of it (header comment), inside its neighbour blocks
  // (B >= 4): if those blocks hold no solid voxel, s = 0 on the block and its halo; if they are
  // all solid, inside the grid and clear of the cut, s = 1 there. Either way no edge crosses 1/2.
  const int B = block_size_;
  const int c[3] = {b0[0] / B, b0[1] / B, b0[2] / B};
  bool empty = true, full = true;
  for (int z = c[2] - 1; z <= c[2] + 1; ++z) {
    for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
      for (int x = c[0] - 1; x <= c[0] + 1; ++x) {
        if (x < 0 || y < 0 || z < 0 || x >= nb_ || y >= nb_ || z >= nb_) {
          full = false;  // outside the grid reads empty
          continue;
        }
        const std::uint32_t solid = block_solid_[static_cast<std::size_t>(x) +
                                                 static_cast<std::size_t>(nb_) * (y + nb_ * z)];
        if (solid != 0) empty = false;
        const int extent[3] = {std::min(B, grid().n - x * B), std::min(B, grid().n - y * B),
                               std::min(B, grid().n - z * B)};
        if (solid != static_cast<std::uint32_t>(extent[0] * extent[1] * extent[2])) full = false;
      }
    }
  }
  if (full && cut_.enabled) {
    // The neighbourhood's voxels reach (c + 2) B - 1 along x and y: clear of the cut below it.
    full = (c[0] + 2) * B - 1 < cut_.i || (c[1] + 2) * B - 1 < cut_.j;
  }
  return empty || full;
}

void SurfaceMesher::smooth_occupancy(const int b0[3], const int b1[3], int L,
                                     Scratch& scratch) const {
  // s(c) = sum_d w(d) o(c + d) / 64 over the cells [b0 - 1, b1] (header comment), as three
  // passes of the 1-2-1 filter along x, y and z: the same integer sums as the 27-term one.
  const int R = L + 2;  // o over the voxels [b0 - 2, b0 + L - 1] per axis
  std::vector<std::uint8_t>& o_ = scratch.o;
  o_.assign(static_cast<std::size_t>(R) * R * R, 0);
  auto oidx = [R](int x, int y, int z) {
    return static_cast<std::size_t>(x) +
           static_cast<std::size_t>(R) * (static_cast<std::size_t>(y) + static_cast<std::size_t>(R) * z);
  };
  const int hi[3] = {b1[0] - b0[0] + 3, b1[1] - b0[1] + 3, b1[2] - b0[2] + 3};  // last local + 1
  for (int z = 0; z <= hi[2]; ++z) {
    for (int y = 0; y <= hi[1]; ++y) {
      for (int x = 0; x <= hi[0]; ++x) {
        o_[oidx(x, y, z)] = occupied(b0[0] - 2 + x, b0[1] - 2 + y, b0[2] - 2 + z) ? 1 : 0;
      }
    }
  }
  // Pass a filters along axis a the cells 1..hi-1 of that axis, all of the axes not yet passed.
  // Pass a: axes 0..a in [1, hi - 1] (filtered), the later ones in [0, hi] (still needed).
  std::vector<int>& t = scratch.filter;
  std::vector<int>& u = scratch.filter_out;
  t.assign(o_.begin(), o_.end());
  u.resize(t.size());
  for (int a = 0; a < 3; ++a) {
    const std::size_t step = a == 0 ? 1 : (a == 1 ? R : static_cast<std::size_t>(R) * R);
    int lo[3], top[3];
    for (int b = 0; b < 3; ++b) {
      lo[b] = b <= a ? 1 : 0;
      top[b] = b <= a ? hi[b] - 1 : hi[b];
    }
    for (int z = lo[2]; z <= top[2]; ++z) {
      for (int y = lo[1]; y <= top[1]; ++y) {
        for (int x = lo[0]; x <= top[0]; ++x) {
          const std::size_t m = oidx(x, y, z);
          u[m] = t[m - step] + 2 * t[m] + t[m + step];
        }
      }
    }
    t.swap(u);
  }
  for (int z = 1; z < hi[2]; ++z) {
    for (int y = 1; y < hi[1]; ++y) {
      for (int x = 1; x < hi[0]; ++x) {
        scratch.s[static_cast<std::size_t>(x - 1) +
           static_cast<std::size_t>(L) *
               (static_cast<std::size_t>(y - 1) + static_cast<std::size_t>(L) * (z - 1))] =
            static_cast<float>(t[oidx(x, y, z)]) / 64.0f;
      }
    }
  }
}

void SurfaceMesher::mesh_block(int block, Scratch& scratch) {
  BlockMesh& out = blocks_[block];
  out.vertices.clear();
  out.indices.clear();
  ++out.version;
  const int B = block_size_;
  const int b0[3] = {(block % nb_) * B, ((block / nb_) % nb_) * B, (block / (nb_ * nb_)) * B};
  int b1[3];
  for (int a = 0; a < 3; ++a) b1[a] = std::min(grid().n, b0[a] + B);
  // s over the block + 1 voxel halo: local index (c - b0 + 1).
  const int L = B + 2;
  std::vector<float>& s_ = scratch.s;
  s_.assign(static_cast<std::size_t>(L) * L * L, 0.0f);
  auto sidx = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i - b0[0] + 1) +
           static_cast<std::size_t>(L) * (static_cast<std::size_t>(j - b0[1] + 1) +
                                          static_cast<std::size_t>(L) * (k - b0[2] + 1));
  };
  const int pad = field_ != nullptr ? field_->padding() : 0;
  const float half_voxel = 0.5f * static_cast<float>(grid().voxel_size);
  if (field_ != nullptr) {
    // Samples all at c_out (s = -c_out < 0, the cut only lowers s): no cell inside, no quad.
    // At stride k the voxel centres c in [b0 - 1, b1] read the cells of samples floor(c / k) + P
    // and the next (clamped to the lattice), by the field's interpolation.
    const int stride = field_->stride();
    const int last = field_->samples_per_axis() - 1;
    const auto below = [&](int c) {  // floor(c / k) + P
      return (c >= 0 ? c / stride : -((-c + stride - 1) / stride)) + pad;
    };
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::clamp(below(b0[a] - 1), 0, last);
      hi[a] = std::clamp(below(b1[a]) + (stride > 1 ? 1 : 0), 0, last);
    }
    if (field_->all_outside(lo, hi)) return;
    // Deep inside: every sample the block reads at the inside clamp, so s = -phi >= c_in > iso
    // at every centre (at stride k > 1 phi interpolates those samples only) and no edge changes
    // sign: no quad, unless the centre cut lowers some centres of [b0 - 1, b1]. Skipping it
    // leaves the mesh as it was (empty) and saves the per-centre reads of the tooth's interior.
    const bool cut_reaches = cut_.enabled && b1[0] >= cut_.i && b1[1] >= cut_.j;
    // The samples of [lo, hi], read once (the skip's test, and at k = 1 the values).
    std::vector<float>& samples = scratch.samples;
    samples.resize(static_cast<std::size_t>(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) *
                   (hi[2] - lo[2] + 1));
    read_field_samples(*field_, lo, hi, samples.data());
    const float inside = static_cast<float>(-field_->inside_clamp());
    if (!cut_reaches &&
        std::all_of(samples.begin(), samples.end(), [&](float v) { return v == inside; })) {
      return;
    }
    // s at the centres [b0 - 1, b1], x fastest: k = 1, the sample at the centre itself (bit for
    // bit the field's; sample c + P, inside [lo, hi] unclamped as P >= 1 and m >= n + 2 P); else
    // phi there, float(value(centre)) (view/field_values.h).
    const int w[3] = {b1[0] - b0[0] + 2, b1[1] - b0[1] + 2, b1[2] - b0[2] + 2};
    const float* v = samples.data();
    std::size_t step_y = static_cast<std::size_t>(hi[0] - lo[0] + 1);
    std::size_t step_z = step_y * static_cast<std::size_t>(hi[1] - lo[1] + 1);
    std::size_t first = static_cast<std::size_t>(b0[0] - 1 + pad - lo[0]) +
                        step_y * static_cast<std::size_t>(b0[1] - 1 + pad - lo[1]) +
                        step_z * static_cast<std::size_t>(b0[2] - 1 + pad - lo[2]);
    if (stride > 1) {
      const int c0[3] = {b0[0] - 1, b0[1] - 1, b0[2] - 1};
      scratch.values.resize(static_cast<std::size_t>(w[0]) * w[1] * w[2]);
      field_values_at_voxel_centres(*field_, grid(), c0, b1, &samples, scratch.values.data());
      v = scratch.values.data();
      step_y = static_cast<std::size_t>(w[0]);
      step_z = step_y * static_cast<std::size_t>(w[1]);
      first = 0;
    }
    for (int k = b0[2] - 1; k <= b1[2]; ++k) {
      for (int j = b0[1] - 1; j <= b1[1]; ++j) {
        const float* row = v + first + step_y * static_cast<std::size_t>(j - b0[1] + 1) +
                           step_z * static_cast<std::size_t>(k - b0[2] + 1);
        for (int i = b0[0] - 1; i <= b1[0]; ++i) {
          float s = -row[i - b0[0] + 1];
          if (cut_.enabled && i >= cut_.i && j >= cut_.j) s = std::min(s, -half_voxel);
          s_[sidx(i, j, k)] = s;
        }
      }
    }
  } else {
    if (uniform_neighbourhood(b0)) return;  // no crossing: no quad (and the mesh stays empty)
    smooth_occupancy(b0, b1, L, scratch);
  }
  auto s_at = [&](int i, int j, int k) { return s_[sidx(i, j, k)]; };
  const float h = static_cast<float>(grid().voxel_size);
  const Eigen::Vector3f origin = grid().origin.cast<float>();

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
    if (occupied(i, j, k)) return grid().at(i, j, k);
    std::array<int, kMaterialCount> count{};
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (occupied(i + dx, j + dy, k + dz)) ++count[grid().at(i + dx, j + dy, k + dz)];
        }
      }
    }
    int best = 1;
    for (int m = 2; m < kMaterialCount; ++m) {
      if (count[m] > count[best]) best = m;
    }
    return static_cast<float>(best);
  };

  // A dual cell's vertex is shared by the quads around it: computed once per block (the same
  // function of s, so the same vertex). The cells c in [b0 - 1, b1 - 1]: index c - b0 + 1.
  const std::size_t C = static_cast<std::size_t>(B) + 1;
  scratch.cell_done.assign(C * C * C, 0);
  scratch.cell_vertex.resize(C * C * C);
  const auto cell_index = [&](const int c[3]) {
    return static_cast<std::size_t>(c[0] - b0[0] + 1) +
           C * (static_cast<std::size_t>(c[1] - b0[1] + 1) +
                C * static_cast<std::size_t>(c[2] - b0[2] + 1));
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
              const std::size_t cell = cell_index(c);
              if (scratch.cell_done[cell] == 0) {
                cell_vertex(c[0], c[1], c[2], &scratch.cell_vertex[cell]);
                scratch.cell_done[cell] = 1;
              }
              MeshVertex v = scratch.cell_vertex[cell];
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
  // The solid's x and y extent, a row at a time (its first and last solid voxel): the same
  // bounds as testing every voxel, without the per-voxel bounds checks (issue #30: 512^3).
  int lo[2] = {grid.n, grid.n}, hi[2] = {-1, -1};
  const std::size_t n = static_cast<std::size_t>(grid.n);
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint8_t* row = grid.voxels.data() + n * (j + n * k);
      std::size_t first = 0;
      while (first < n && row[first] == 0) ++first;
      if (first == n) continue;
      std::size_t last = n - 1;
      while (row[last] == 0) --last;
      lo[0] = std::min(lo[0], static_cast<int>(first));
      hi[0] = std::max(hi[0], static_cast<int>(last));
      lo[1] = std::min(lo[1], static_cast<int>(j));
      hi[1] = std::max(hi[1], static_cast<int>(j));
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
