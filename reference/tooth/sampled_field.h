// The tooth as a smooth field (issue #30; BEYOND THE THESIS; derivation in
// docs/derivations/field_contact.md): a sampled signed distance to the tooth's *source* surface
// (the mesh's triangles, the procedural molar's implicit surface, a scan's iso-surface), stored in a narrow band of
// sparse bricks and interpolated trilinearly, so that the surface sits between the samples
// (sub-voxel) instead of on the voxel staircase.
//
// Frames and units: world frame {O}, metres. Samples sit at the centres of every k-th voxel of
// the tooth grid (voxel_grid.h; k >= 1 the stride, FieldBand::stride) and continue P samples
// beyond the grid on every side (so that the band around a surface near the grid's edge is
// whole): sample s = (s_x, s_y, s_z), s_a in [0, M), is at
//   p(s) = field_origin + H s,   H = k h,   field_origin = grid.origin + (0.5 - k P) h,
// i.e. the centre of voxel k (s - P) (Stride: every formula below holds with h read as H, the
// lattice's spacing; the sign still comes from the voxel the sample sits in; k = 1 is the field
// of one sample per voxel centre, bit for bit). Its value is
//   v(s) = clamp(sigma(s) d(s), -c_in, c_out),
// d(s) the exact (unsigned) distance from p(s) to the source surface (nearest triangle), sigma(s)
// = -1 if voxel k (s - P) is solid in the tooth grid, else +1 (the voxeliser's own inside test:
// the mesh's winding number, the molar's implicit function or the scan's class at the voxel
// centre, so the field's sign and the materials agree sample by sample). Clamping keeps the band narrow:
// only the outside within c_out matters to the tool (the surface proxy keeps its centre at
// phi >= rho - s), the inside only down to c_in.
//
// The field phi(x) is the trilinear interpolant of v over the lattice (coordinates clamped to the
// lattice outside it). It is continuous everywhere, and inside one cell its gradient component
// along axis a is the bilinear interpolation of the four a-edge differences / h; hence
//   |grad phi| <= L_cell = sqrt(sum_a max_{a-edges of the cell} (dv / h)^2)
// and phi is L-Lipschitz with L = max over cells of L_cell (`lipschitz()`, measured from the
// stored samples at build: a bound of the stored field itself, whatever the source). For exact
// distances of a surface |dv| <= h on every edge (d is 1-Lipschitz and clamping keeps that), so
// L <= sqrt(3); on smooth surfaces L is close to 1.
//
// Why trilinear and not tricubic: trilinear interpolation of a 1-Lipschitz sample set has the
// provable cell bound above, costs 8 samples per query, and reproduces planes exactly; its
// gradient is discontinuous across cell faces by O(h kappa) (kappa the surface curvature), far
// below the voxel staircase's. Tricubic (Catmull-Rom) would need 64 samples, may overshoot
// (phi can dip below both neighbours: a negative lobe in free space), and has no cheap
// Lipschitz bound, and the no-tunnelling proof rests on that bound.
//
// Storage: bricks of 8^3 samples (float: the values are below ~1 mm, so float keeps ~0.1 nm) for
// every brick holding a sample with -c_in < v < c_out; a flat index (one int32 per brick slot)
// names each slot's brick, or says that the whole slot is outside (+c_out) or inside (-c_in).
// Memory is proportional to the surface's area times the band's width (the index adds 4 bytes
// per 512 voxels).
//
// Build (`build_sampled_field`): exact point-triangle distances for the samples within 2 h of
// each triangle (each triangle's box grown by 2 h; so every sample within 2 h of the surface is
// exact), then the band is grown layer by layer: a sample next to an assigned one takes the
// nearest of its assigned face neighbours' nearest triangles, and finally walks the mesh from
// that triangle (the triangles around its vertices) while a nearer one is found. The result is
// the distance to a real triangle, so never below the truth; on the test sphere it is exact to
// the chord error (tests/tooth/sampled_field_test.cc).
//
// Real-time: value() and gradient() read 8 samples through the index; nothing allocates or throws.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "reference/core/setup_threads.h"
#include "reference/core/types.h"
#include "reference/tooth/triangle_mesh.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

inline constexpr int kFieldBrick = 8;  // samples per brick edge

// The band's half widths [m]: outside (c_out) and inside (c_in). Both are raised to at least
// 2 h at build.
struct FieldBand {
  double outside_m = 1.0e-3;
  double inside_m = 0.0;  // 0: 2 H
  // The stride k >= 1 (issue #30): samples at every k-th voxel centre, spacing H = k h (header
  // comment "Stride"). 1: one sample per voxel centre.
  int stride = 1;
};

// The band a surface proxy of tip radius rho needs: it reads phi where phi < rho + s (s <= rho/4)
// and the gradient there; c_out = 1.25 rho + 2 H leaves two cells of margin (H = stride h).
FieldBand field_band_for_tip(double rho, double voxel_size, int stride = 1);

// The spacing rule (docs/derivations/field_contact.md §7): the largest field spacing H_max a
// tip of radius rho admits,
//   H_max = min(H_wall, H_ripple),  H_wall = (1 - 1e-9) 2 (rho - rho/4) / sqrt(3) = 0.866 rho,
//   H_ripple = rho eps_aim / c_ripple = 0.357 rho  (eps_aim = 0.02, c_ripple = 0.056),
// H_wall from no tunnelling (every point of the source surface has phi <= sqrt(3) H / 2, which
// must stay below the proxy's rho - s, s <= rho / 4), H_ripple from the sliding ripple (linear
// in H / rho, measured coefficient c_ripple; the aim eps_aim).
inline constexpr double kFieldRippleAim = 0.02;
inline constexpr double kFieldRipplePerSpacing = 0.056;  // ripple / (H / rho), §7
double field_max_spacing(double rho);
// The stride a field on voxels of size h gets for the smallest tip radius rho: the largest k >= 1
// with k h <= H_max(rho) when spacing_m is 0 (automatic); else the largest k >= 1 with k h <=
// spacing_m (1 + 1e-9). spacing_m must be 0 or finite and >= h (sim/scene.cc validates it).
int field_stride_for(double rho, double voxel_size, double spacing_m = 0.0);

struct FieldSample {
  double value = 0.0;  // phi(x) [m]
  Vec3 gradient = Vec3::Zero();  // grad phi(x) (analytic gradient of the trilinear interpolant)
};

class SampledField {
 public:
  SampledField() = default;

  // phi(x) and its gradient (the cell's; on a cell face, the cell above).
  FieldSample sample(const Vec3& x) const;
  double value(const Vec3& x) const { return sample(x).value; }
  // The Lipschitz constant L of phi (header comment).
  double lipschitz() const { return lipschitz_; }
  // The tooth grid's voxel size h, and the field's spacing H = stride() h (the lattice's step).
  double voxel_size() const { return voxel_h_; }
  double spacing() const { return h_; }
  int stride() const { return stride_; }
  double outside_clamp() const { return c_out_; }
  double inside_clamp() const { return c_in_; }
  // Whether phi at x is the inside clamp at all 8 corners (deep inside: no gradient there).
  bool deep_inside(const Vec3& x) const;
  // Stored value of sample s (lattice coordinates, each in [0, samples_per_axis())).
  float at(int sx, int sy, int sz) const;
  // Whether every sample of the box [lo, hi] (inclusive lattice coordinates in [0, m)) lies in a
  // brick slot marked all outside, i.e. holds c_out (the view skips such blocks; issue #30).
  bool all_outside(const int lo[3], const int hi[3]) const;
  int samples_per_axis() const { return m_; }
  int padding() const { return pad_; }  // P
  Vec3 sample_position(int sx, int sy, int sz) const {
    return origin_ + h_ * Vec3(sx, sy, sz);
  }
  // Moves the field by t [m] (the simulator places the tooth after building it).
  void translate(const Vec3& t) { origin_ += t; }
  std::size_t brick_count() const { return bricks_.size() / kBrickSamples; }
  // Bytes of bricks, their row bounds and the index.
  std::size_t memory_bytes() const {
    return (bricks_.size() + row_bounds_.size()) * sizeof(float) +
           index_.size() * sizeof(std::int32_t);
  }
  // The drilling edit's row bound (reference/tooth/field_edit_core.h): B >= |v(s)| for every
  // sample s with v(s) < c_out (as float) among the kFieldBrick samples (bx kFieldBrick + i, sy,
  // sz), i in [0, kFieldBrick); B < 0 when the row has none. Kept by build and raise() (values
  // only rise: an outside value's |v| may grow and raises B, an inside one's only falls), so it
  // bounds the row after every edit; not necessarily the least bound.
  float row_bound(int bx, int sy, int sz) const {
    const std::int32_t id = index_[slot(bx, sy / kFieldBrick, sz / kFieldBrick)];
    if (id >= 0) {
      return row_bounds_[static_cast<std::size_t>(id) * kBrickRows +
                         static_cast<std::size_t>(sy % kFieldBrick +
                                                  kFieldBrick * (sz % kFieldBrick))];
    }
    return id == kAllOutside ? -1.0f : static_cast<float>(c_in_);
  }

  static constexpr int kBrickSamples = kFieldBrick * kFieldBrick * kFieldBrick;
  static constexpr int kBrickRows = kFieldBrick * kFieldBrick;  // x rows of a brick
  static constexpr std::int32_t kAllOutside = -1;
  static constexpr std::int32_t kAllInside = -2;

  // Editing (drilling, reference/tooth/field_contact.h edit_field_for_removed_voxels; docs/
  // derivations/field_contact.md §5). Outside the tick: reserve room for `spare` more bricks
  // (allocates once). In the tick: raise() and include_cells() neither allocate nor throw.
  void reserve_spare_bricks(std::size_t spare);
  // Bricks that raise() may still allocate without growing the storage.
  std::size_t spare_bricks() const {
    return (bricks_.capacity() - bricks_.size()) / static_cast<std::size_t>(kBrickSamples);
  }
  // v(s) <- max(v(s), value) (value clamped to [-c_in, c_out]); a slot without a brick takes one
  // from the spare room, filled with its clamp value. Returns false, changing nothing, when it
  // needs a brick and none is spare. s must be in [0, samples_per_axis())^3.
  bool raise(int sx, int sy, int sz, double value);
  // Raises lipschitz() to the cell bound of every cell with a corner in the sample box
  // [lo, hi] (so that it bounds the field again after raise(); header comment).
  void include_cells(const int lo[3], const int hi[3]);
  // The cell bound L_cell of the cell with lower corner (x, y, z), each in [0, m - 2].
  double cell_lipschitz(int x, int y, int z) const;
  // The drilling edit's radius in voxels, R_v = ceil(c_out / h + 1): the voxel centres a removed
  // voxel's edit may concern lie within R_v voxels of it (max norm; reference/tooth/
  // field_contact.h); the view's re-mesh halo (view/surface_mesh.h).
  int edit_radius_voxels() const { return static_cast<int>(std::ceil(c_out_ / voxel_h_ + 1.0)); }
  // The same in field samples, R = ceil(R_v / k): the samples s with |k (s - P) - c|_inf <= R_v
  // (c the removed voxel) lie within R of floor(c / k) + P (max norm). At k = 1, R = R_v. The one
  // definition for the edit (both twins).
  int edit_radius() const { return (edit_radius_voxels() + stride_ - 1) / stride_; }
  // The voxel whose centre sample s (one coordinate) sits at: k (s - P) (beyond the grid when
  // outside [0, n)).
  int voxel_of_sample(int s) const { return stride_ * (s - pad_); }

 private:
  friend SampledField build_sampled_field(const VoxelGrid&, const TriangleMesh&, const FieldBand&,
                                          int);

  std::size_t slot(int bx, int by, int bz) const {
    return static_cast<std::size_t>(bx) +
           static_cast<std::size_t>(nb_) *
               (static_cast<std::size_t>(by) + static_cast<std::size_t>(nb_) * bz);
  }

  Vec3 origin_ = Vec3::Zero();  // position of sample (0, 0, 0)
  double h_ = 0.0;        // the spacing H = k h
  double voxel_h_ = 0.0;  // the grid's voxel size h
  int stride_ = 1;        // k
  int m_ = 0;    // samples per axis (a multiple of kFieldBrick)
  int nb_ = 0;   // bricks per axis
  int pad_ = 0;  // P
  double c_out_ = 0.0, c_in_ = 0.0;
  double lipschitz_ = 1.0;
  std::vector<std::int32_t> index_;  // nb^3: brick id, kAllOutside or kAllInside
  std::vector<float> bricks_;        // brick id * 512 + x + 8 (y + 8 z)
  std::vector<float> row_bounds_;    // brick id * 64 + y + 8 z: row_bound()
  // row_bounds_ of brick `id` from its stored samples (build).
  void measure_row_bounds(std::int32_t id);
};

// Exact distance from p to triangle (a, b, c) (Voronoi regions of the vertices, edges and face).
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// The field of the closed surface `surface` (world frame, the grid's) with signs from the solid
// voxels of `grid` (header comment). `surface` must bound the grid's solid (the mesh it was
// voxelised from, or the triangulated implicit surface below). The exact distances (layer 0) and
// the descent run on `threads` threads (reference/core/setup_threads.h; <= 0: setup_threads()),
// each on its own z-slab of bricks, every sample seeing the triangles in the one-thread order:
// the field is the one-thread field bit for bit, whatever the thread count.
SampledField build_sampled_field(const VoxelGrid& grid, const TriangleMesh& surface,
                                 const FieldBand& band, int threads = 0);

// The surface between the grid's solid and empty voxel centres as triangles, by marching
// tetrahedra over the cells of voxel centres (Kuhn's six tetrahedra per cell): one vertex on each
// tetrahedron edge that joins a solid centre p_in and an empty one p_out, at place(p_in, p_out)
// (asked once per edge, in the order of the vertices; it should return a point of the segment, so
// that every sample the surface separates has its sign from the grid). Centres beyond the grid
// count as empty (as in the grid and the field), so the surface is closed even where solid voxels
// touch the grid's boundary layer (the procedural molar's and the tests' grids keep an empty
// margin: no cell beyond it has a solid corner, and the surface is the one of the cells inside).
TriangleMesh triangulate_voxel_signs(
    const VoxelGrid& grid, const std::function<Vec3(const Vec3& p_in, const Vec3& p_out)>& place);

// A surface vertex's edge: the voxel centres (indices in [-1, n]) of its solid end `in` and its
// empty end out(), which is in + d with d_a in {-1, 0, 1} (the corners of one cell) kept in 2 bits
// an axis: 8 bytes a vertex (issue #30: the edges live beside the vertices while they are placed).
// p_in = grid.center(in), p_out = grid.center(out(0), out(1), out(2)).
struct VoxelEdge {
  std::int16_t in[3];
  std::uint8_t step;  // d_a + 1 in bits 2a and 2a + 1
  int out(int a) const { return in[a] + ((step >> (2 * a)) & 3) - 1; }
};
static_assert(sizeof(VoxelEdge) == 8);
// triangulate_voxel_signs without placing the vertices: the triangles (and groups) as it makes
// them, `edges` (resized) the edge of each vertex, and the vertices left at zero (issue #30: the
// placements are independent of each other, so triangulate_implicit makes them on several
// threads). Throws std::invalid_argument when the grid has more than 32766 voxels a side.
TriangleMesh triangulate_voxel_edges(const VoxelGrid& grid, std::vector<VoxelEdge>* edges);

// The surface of an implicit solid {p : inside(p)} as triangles: triangulate_voxel_signs with each
// vertex placed on its edge where `inside` changes, by bisection to 2^-40 of the edge. The signs
// at the voxel centres are the grid's solid voxels (which must be inside() at the centres, as
// voxelize_procedural_molar makes them).
// `inside` is any callable bool(const Vec3&), called directly (a template: the bisections are
// 40 calls per surface edge, ~10^8 at 512^3, issue #30), not through std::function, and from
// `threads` threads at once (reference/core/setup_threads.h; <= 0: setup_threads()), each placing
// a contiguous range of the vertices: `inside` must be safe to call concurrently (a pure test).
// Every vertex is placed by the same bisection whatever the thread count, so the mesh is the
// one-thread mesh bit for bit.
template <class Inside>
TriangleMesh triangulate_implicit(const VoxelGrid& grid, const Inside& inside, int threads = 0) {
  std::vector<VoxelEdge> edges;
  TriangleMesh mesh = triangulate_voxel_edges(grid, &edges);
  constexpr int kChunk = 4096;  // vertices a task
  const int tasks = static_cast<int>((edges.size() + kChunk - 1) / kChunk);
  parallel_tasks(tasks, threads, [&](int task) {
    const std::size_t end = std::min(edges.size(), static_cast<std::size_t>(task + 1) * kChunk);
    for (std::size_t v = static_cast<std::size_t>(task) * kChunk; v < end; ++v) {
      const VoxelEdge& e = edges[v];
      Vec3 p_in = grid.center(e.in[0], e.in[1], e.in[2]);
      Vec3 p_out = grid.center(e.out(0), e.out(1), e.out(2));
      for (int it = 0; it < 40; ++it) {
        const Vec3 mid = 0.5 * (p_in + p_out);
        (inside(mid) ? p_in : p_out) = mid;
      }
      mesh.vertices[v] = 0.5 * (p_in + p_out);
    }
  });
  return mesh;
}

}  // namespace dentsim
