// The contact's material without its nearest voxel (issue #30, stop 49): a pyramid of blocks of
// the grid, each holding the one material of its solid voxels, kEmpty if it has none, or kMixed.
//
// Why. The field model's servo asks each contact tick for the material of the solid voxel nearest
// to the proxy g (reference/tooth/sdf.h proxy_material: sd(tooth, g, 2 rho)). Finding that voxel
// exactly (SurfaceCutSet::material_alone's nearest-first walk) reads every exposed voxel whose
// block may be as near as the nearest: in the drill scene the bur sits in the cavity it cut, whose
// wall is nearly a sphere about g, so the walk reads the whole wall, ~N^2 voxels. But the contact
// needs only the voxel's material, and where the tooth's materials are uniform about g a few
// large blocks prove it.
//
// The certificate (only() below, SurfaceCutSet::material). Let s be a voxel solid now with
// D(s) < (2 rho)^2 (D: box_distance2's double, reference/tooth/sdf.h), m its material. The
// reference's voxel v* minimises (D(v), v) over the solid voxels with D < (2 rho)^2, so it exists
// and D(v*) <= D(s). A block's bound is D of its box, clipped to the grid (the same per-axis terms
// at the planes origin + h i, summed (x + y) + z); each of the block's voxels has its planes within
// the block's (fl(h i) and fl(origin + .) are monotone in i), so its terms, and their rounded sum,
// are no smaller: bound(B) <= D(v) for every v in B, and for every block holding v*, at every
// level, bound <= D(s). So if every block with bound <= D(s) is kEmpty or m, or kMixed with each
// child so (recursively; a kMixed block of level 0 passes if none of its voxels solid now and of
// another material has D <= D(s), its voxels' own D), then the level-0 block holding v* or an
// ancestor of it was met and passed: it held a solid voxel (v* was solid at construction:
// removals never add solid), so it was not kEmpty; it was m, or v* (solid, D(v*) <= D(s)) was
// read and is m. So v* is of material m: the reference's material, bitwise, whatever the voxels'
// exposure and g's position on a grid plane.
//
// The status stays sound while the tooth only loses voxels (every solid voxel now was solid, with
// the same material, at construction); a block that lost its other material stays kMixed (only
// the work grows). No hook on removals.
//
// A block of level 0 of one other material is read voxel by voxel as a kMixed one (it passes if
// drilling took its voxels within the ball; the proof reads it as a kMixed block's), and one of
// level 1 descended into (collide50; above, such a block refuses).
//
// The witness (collide50). Where the refusal comes from a level-0 block's voxels, the block's
// solid voxel w of another material with the least D (< D(s); a tie names none) is a voxel solid
// now with D(w) < D(s) < (2 rho)^2: an s for the certificate again, with w's material and a
// smaller ball (SurfaceCutSet::material asks again, a few rounds: D falls each round). With g on
// a junction of materials the first s is often on the wrong side; the second certifies.
//
// The cost. The descent starts at the finest level whose blocks are at least the ball's radius
// sqrt(D(s)) across (collide50; until then at the root): the blocks of the ball's box there (at
// most 6 per axis, with a block of margin each side), then the kMixed ones' children near the
// ball: independent of N (the levels above are not read). Where two materials meet near the ball, the
// kMixed level-0 blocks (4^3) it meets are read voxel by voxel (64 bytes each); where a voxel of
// another material is as near as s the certificate fails (the caller's exact walk answers).
//
// Real-time: only() neither allocates nor throws (a fixed stack); the constructor allocates
// (~n^3 / 56 bytes: 2.4 MB at 512^3) and reads every voxel once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "reference/tooth/voxel_grid.h"

namespace dentsim::fast {

class MaterialBlocks {
 public:
  static constexpr std::uint8_t kMixed = 0xff;
  static constexpr int kEdge = 4;        // level 0's block edge [voxels] (the grid's if smaller)
  static constexpr int kMaxLevels = 12;  // more (n > 2^13) and only() refuses

  // No block (levels() 0: a cut set that never asks for the material, SurfaceCutSet's flag).
  MaterialBlocks() = default;
  // The status of every block of `grid` (n a power of two). Allocates.
  explicit MaterialBlocks(const VoxelGrid& grid);

  int levels() const { return static_cast<int>(across_.size()); }
  // Blocks per axis at `level` and their edge [voxels].
  int across(int level) const { return across_[static_cast<std::size_t>(level)]; }
  int edge(int level) const { return edge0_ << level; }
  // The block's material (kEmpty: no solid voxel; kMixed: more than one).
  std::uint8_t status(int level, int x, int y, int z) const {
    const std::size_t a = static_cast<std::size_t>(across(level));
    return status_[offset_[static_cast<std::size_t>(level)] + static_cast<std::size_t>(x) +
                   a * (static_cast<std::size_t>(y) + a * static_cast<std::size_t>(z))];
  }

  // Whether no voxel solid in `grid` with D <= d2 at x has a material other than m (header
  // comment): every block with bound <= d2 is kEmpty or m, or kMixed with each child so, and a
  // kMixed block of level 0 has no voxel solid now, of another material, with D <= d2 (its voxels
  // read from `grid`). `grid` is the constructor's (it may have lost solid voxels since). No
  // allocation, no throw.
  bool only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m) const {
    return only(grid, x, d2, m, nullptr);
  }
  // A voxel solid now, of a material other than only()'s m, with D < only()'s d2 (found false:
  // none named).
  struct Witness {
    bool found = false;
    std::size_t voxel = 0;
    double d2 = 0.0;
  };
  // only(), and where it refuses on a level-0 block's voxels, that block's solid voxel of another
  // material with the least D (the first in the grid's order among equals) into *witness if its D
  // is < d2 (a tie names none). A caller re-asks from the witness, with its D and material
  // (SurfaceCutSet::material): a smaller ball, about the other side of a junction of materials.
  // A block of one other material is read like a kMixed one at level 0 (its voxels may all have
  // been removed since), and below level kPureDescent descended into; above, it refuses.
  bool only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m,
            Witness* witness) const;
  static constexpr int kPureDescent = 2;  // a block of another material of level < this is read
  static constexpr int kStartSpan = 6;    // only()'s start blocks per axis at most

  // Blocks whose bound only() computed, and kMixed level-0 blocks whose voxels it read (tests and
  // benchmarks).
  long blocks_read() const { return blocks_read_; }
  long mixed_read() const { return mixed_read_; }

 private:
  int edge0_ = 1;
  std::vector<int> across_;
  std::vector<std::size_t> offset_;
  std::vector<std::uint8_t> status_;
  // only() on level-0 block (bx, by, bz), kMixed or of another material: its voxels (and the
  // witness, if not null, where it refuses).
  bool voxels_only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m, int bx, int by,
                   int bz, Witness* witness) const;

  mutable long blocks_read_ = 0;
  mutable long mixed_read_ = 0;
};

}  // namespace dentsim::fast
