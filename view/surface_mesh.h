// A smooth, incrementally updated surface of the voxel tooth for the 3-D view (issue #19).
//
// Field: each voxel centre c = (i, j, k) carries the smoothed occupancy
//   s(c) = sum_{d in {-1,0,1}^3} w(d) o(c + d),  w(d) = w1(dx) w1(dy) w1(dz) / 64,  w1 = (1, 2, 1)
// with o = 1 for a solid voxel that is not cut away and 0 otherwise (also outside the grid), so
// s in [0, 1] and s < 1/2 outside the grid. A centre is inside when s >= 1/2.
//
// Surface (naive surface nets on s, Gibson 1998 "Constrained elastic surface nets"): every dual
// cell (the cube between 8 neighbouring centres, named by its minimum centre) whose corners are
// not all inside or all outside holds one vertex: the mean of the points where s crosses 1/2 on
// its 12 edges (linear interpolation). Every grid edge from an inside centre a to an outside
// neighbour a + d gives one quad joining the vertices of the 4 dual cells around that edge, wound
// counter-clockwise seen from outside (from a + d), split into two triangles. Vertex normal: the
// normalised -grad s of the dual cell (differences of its 8 corners), so the surface shades
// smoothly. Positions are world [m]: origin + h (c + 1/2) for centre c (voxel_grid.h).
//
// On the tooth's sampled field (the contact model "field", reference/tooth/sampled_field.h; issue
// #30: the view meshes the surface the tool touches): s(c) = -v(c), v the field's sample at the
// voxel centre c (its lattice point c + P), and the level is 0 instead of 1/2; everything else
// is the same. The field's samples are distances to the tooth's source surface, so the crossings
// on the dual cells' edges put the vertices on that surface to the interpolation's accuracy (no
// voxel terraces). A cut-away voxel takes s = min(s, -h/2): outside, its cut face half a voxel
// from the centres it leaves. A field edit (drilling) changes samples within the edit radius R of
// a removed voxel (field_contact.h), so update() dirties the blocks within R + 2 of it.
//
// Material per quad: the material of a if it is solid, else the most frequent material among the
// solid voxels of a's 3x3x3 neighbourhood (ties: the lower id). The cut-away (a quarter removed,
// as in tooth_io/render_png.h) makes voxels with i >= cut_i and j >= cut_j empty for the
// field only, so the cut faces are real surface, coloured by the layers they cross.
//
// Blocks: the grid is split into blocks of B^3 voxels; a quad belongs to the block of its inside
// centre a. A quad depends on s within +-1 of a, hence on o within +-2 of a: a changed voxel v
// dirties exactly the blocks that contain a voxel within +-2 of v (per axis). update() re-meshes
// only those blocks; the result is identical, bit for bit, to meshing the changed grid whole
// (tests/view/surface_mesh_test.cc).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "reference/tooth/sampled_field.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim::view {

struct MeshVertex {
  float p[3];      // world position [m]
  float n[3];      // unit outward normal
  float material;  // Material id (1 enamel, 2 dentin, 3 pulp)
};

struct BlockMesh {
  std::vector<MeshVertex> vertices;
  std::vector<std::uint32_t> indices;  // triangles, indices into vertices
  std::uint64_t version = 0;           // bumped each time the block is re-meshed
};

struct CutAway {
  bool enabled = false;
  int i = 0, j = 0;  // voxels with i >= cut_i and j >= cut_j are removed from the field
};

class SurfaceMesher {
 public:
  static constexpr int kHalo = 2;  // voxels of o a block's quads depend on beyond the block
  // Blocks of 8^3: a drilled ball of 3 voxels re-meshes in ~0.8 ms against ~4 ms with 16^3 and
  // ~130-170 ms for the whole 128^3 tooth (docs/view.md, bench/view_bench.cc).
  static constexpr int kDefaultBlockSize = 8;

  // Meshes `grid` whole. block_size B >= 4.
  explicit SurfaceMesher(const VoxelGrid& grid, int block_size = kDefaultBlockSize,
                         CutAway cut = {});
  // Meshes the zero level of `field`, the sampled field of `grid` (header comment); `field` must
  // outlive the mesher, and update() reads it as it is then. Null: the voxels, as above.
  SurfaceMesher(const VoxelGrid& grid, const SampledField* field,
                int block_size = kDefaultBlockSize, CutAway cut = {});

  // Meshes `grid` as the constructor above does, but reads the caller's grid instead of copying
  // it (a 512^3 tooth is 128 MiB; issue #30): `grid` must outlive the mesher and not change
  // while it lives. Such a mesher cannot update() (it throws std::logic_error). The meshes are
  // the same as a copying mesher's. Its blocks are meshed on `threads` threads (reference/core/
  // setup_threads.h parallel_tasks; <= 0: setup_threads()), each block by one thread into its own
  // BlockMesh, so the blocks are the one-thread mesher's bit for bit whatever the count (issue
  // #30: the pictures of a 512^3 tooth). The other constructors mesh on the calling thread (the
  // live view's mesher runs beside the servo).
  static SurfaceMesher borrowing(const VoxelGrid& grid, const SampledField* field = nullptr,
                                 int block_size = kDefaultBlockSize, CutAway cut = {},
                                 int threads = 0);

  // The grid changed at the flat voxel indices `changed` (the mesher's own copy is updated from
  // `grid`); re-meshes the dirty blocks and returns their ids, sorted.
  std::vector<int> update(const VoxelGrid& grid, std::span<const std::size_t> changed);
  // With a field, when the caller knows which of its samples changed (the live view diffs them
  // around the edit: view/live_tooth.h): the grid changed at the voxels `changed` and the field
  // at the samples `samples` (lattice coordinates, each in [0, samples_per_axis())). Re-meshes
  // only the blocks that read them: a voxel's within kHalo of it (its occupancy: the quads'
  // materials; the field's samples carry the surface), a sample's those with a voxel within 1
  // (the dual cells' reach) of a voxel centre whose value reads it (stride 1: the centre
  // s - P; stride k: every centre c with floor(c / k) + P in {s - 1, s}, the interpolation's
  // cell). Returns their ids, sorted. The mesh is the one update() makes (which assumes every
  // sample within the edit radius of a voxel changed), bit for bit, from fewer blocks.
  std::vector<int> update(const VoxelGrid& grid, std::span<const std::size_t> changed,
                          std::span<const std::array<int, 3>> samples);
  // Changes the cut-away and re-meshes everything.
  void set_cut(CutAway cut);

  const VoxelGrid& grid() const { return borrowed_ != nullptr ? *borrowed_ : own_; }
  int block_size() const { return block_size_; }
  int blocks_per_axis() const { return nb_; }
  const std::vector<BlockMesh>& blocks() const { return blocks_; }
  // Hands the meshes over (a one-shot picture's renderer frees each once the GL holds it; issue
  // #30). Afterwards blocks() is empty and the mesher is done: no update() or set_cut().
  std::vector<BlockMesh> take_blocks() {
    std::vector<BlockMesh> out;
    out.swap(blocks_);
    return out;
  }
  const CutAway& cut() const { return cut_; }
  std::size_t triangle_count() const;
  // The blocks update() would re-mesh for a change of voxel (i, j, k), sorted.
  std::vector<int> blocks_touched_by(int i, int j, int k) const;

 private:
  // A block's working arrays: one per thread meshing blocks.
  struct Scratch {
    std::vector<float> s;                  // s over one block + 1 voxel halo
    std::vector<float> samples;            // the field's samples a block reads
    std::vector<float> values;             // phi at a block's voxel centres (stride k > 1)
    std::vector<std::uint8_t> o;           // o over one block + 2 voxel halo
    std::vector<int> filter, filter_out;   // the separable filter's passes
    std::vector<MeshVertex> cell_vertex;   // each dual cell's vertex, once computed
    std::vector<std::uint8_t> cell_done;   // whether cell_vertex holds it
  };
  // borrowed: the grid read (not copied), else null and `grid` copied.
  SurfaceMesher(const VoxelGrid* borrowed, const VoxelGrid& grid, const SampledField* field,
                int block_size, CutAway cut, int threads);
  void mesh_block(int block, Scratch& scratch);
  // Meshes every block, on threads_ threads.
  void mesh_all();
  // Copies the changed voxels from `grid` (the per-block solid counts follow).
  void copy_voxels(const VoxelGrid& grid, std::span<const std::size_t> changed);
  // Appends the blocks that hold a voxel of the box [lo, hi] (inclusive, clamped to the grid).
  void append_blocks(const int lo[3], const int hi[3], std::vector<int>* out) const;
  // Sorts and de-duplicates `dirty`, re-meshes those blocks and returns them.
  std::vector<int> remesh(std::vector<int> dirty);
  // The two update()s: the voxels `changed` dirty the blocks within `halo` of them, the samples
  // `samples` those that read them.
  std::vector<int> update_voxels(const VoxelGrid& grid, std::span<const std::size_t> changed,
                                 int halo, std::span<const std::array<int, 3>> samples);
  bool occupied(int i, int j, int k) const;
  // The voxels' path (no field): the solid voxels per block, the test that lets mesh_block skip
  // a block whose +-1 block neighbourhood is all empty or all solid (it has no quad), and s over
  // a block and its halo by a separable filter (the same sums as the 27-term definition).
  void count_block_solids();
  bool uniform_neighbourhood(const int b0[3]) const;
  void smooth_occupancy(const int b0[3], const int b1[3], int L, Scratch& scratch) const;

  VoxelGrid own_;                        // the mesher's copy (empty when borrowing)
  const VoxelGrid* borrowed_ = nullptr;  // the caller's grid (borrowing())
  int block_size_;
  int nb_;
  CutAway cut_;
  const SampledField* field_ = nullptr;
  float iso_ = 0.5f;
  // Voxels around a change that the mesh depends on: kHalo on the voxels, the field's edit radius
  // + 2 on a field.
  int halo_ = kHalo;
  int threads_ = 1;  // mesh_all()'s (borrowing()), else 1
  std::vector<BlockMesh> blocks_;
  std::vector<std::uint32_t> block_solid_;  // solid voxels per block (voxels' path)
  Scratch scratch_;                         // update()'s
};

// The cut-away through the centre of the solid's bounding box: removes the +x, +y quarter (seen
// by a camera at azimuth 45 deg, view/camera.h). An empty grid gives a disabled cut.
CutAway centre_cut(const VoxelGrid& grid);

}  // namespace dentsim::view
