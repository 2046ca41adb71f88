// The fast twin of the surface-proxy contact's voxel side (issue #30 "fast/ that earns its name";
// reference: ToothContactProvider::surface_contact_voxels, reference/tooth/tooth_contacts.h): the
// cut set of drilling (reference/tooth/drilling.h collect_cut_set) and the contact's material
// (reference/tooth/sdf.h proxy_material), from the tooth's exposed voxels only. Same voxels, same
// order, same doubles, same material (tests/fast/cut_set_test.cc).
//
// The reference's cost: collect_cut_set lists every solid voxel of the ball (g, R), R =
// cut_band(rho).reach, by an octree descent from the root (FullOctree::query_sphere), and keeps
// the exposed ones (a non-zero neighbour code) with a band depth > 0: at 512^3 and the 0.5 mm bur
// ~8 000 solid voxels for ~900 members. The material asks sd(tooth, g, 2 rho), the nearest solid
// voxel, by a second descent from the root. The twin visits the exposed voxels of the ball's
// bounding box only, once, for both.
//
// SurfaceVoxels: one bit per voxel, set iff its neighbour code is non-zero (reference/tooth/
// neighbors.h), in bricks of 8^3 voxels (64 bytes) held only where the brick had a solid voxel at
// construction (a voxel can become exposed only there: removals never add solid). Inside a brick
// the bits are in Morton order: bit m of the 512 is the voxel whose local coordinates interleave
// to m (x in bit 0, y in bit 1, z in bit 2, ...), so word w (64 bits) is a 4^3 block and byte b of
// a word is a 2^3 block, bit c of the byte its child c = dx + 2 dy + 4 dz. Drilling keeps them
// current at a bounded cost: after drill_tick removed a voxel (and reencode_local re-encoded it and
// its six face neighbours), update() re-reads those seven codes (7 bits per removed voxel).
//
// The order (the reference's, so that the work sums come out the same). query_sphere descends
// depth first: a node's children are pushed in child order 0..7 and popped 7..0, and a node of
// level L-1 (a 2^3 block) appends its voxels in child order 0..7. So the candidates come in
// decreasing Morton code of their 2^3 block, and within a block in increasing child index. With
// the Morton code of a voxel = (its brick's Morton code) * 512 + its bit m, the twin visits the
// bricks in decreasing Morton code (the box's bricks sorted once, and kept while the box stays in
// the same bricks: the band moves little from tick to tick), in a brick its words 7..0, in a word
// its bytes 7..0, and in a byte its bits 0..7. The members are then the reference's: every
// exposed voxel whose box passes the ball test (the squared distance D < R^2 from the same terms
// as sphere_intersects_cells, summed in its order; the octree's node tests never reject a voxel its
// leaf test accepts, octree.h) with cut_band_depth > 0, in that order, up to the vectors' room,
// each the contact with the voxel's material and the depth as its weight.
//
// The culls (stop 46). The pass reads only the blocks that can hold a voxel of the ball: per axis
// it tabulates each voxel's squared gap t_a (the ball test's term; +inf outside the box) and the
// least t_a of each aligned run of 8, 4 and 2 voxels; a brick, a word (4^3) or a byte (2^3) whose
// least terms, summed as a voxel's are, are not < R^2 is skipped unread. Sound: t >= least on each
// axis and rounded addition is monotone, so every voxel of a skipped block fails the ball test
// too. The band depth is cut_band_depth_at of the voxel's squared centre offsets per axis, also
// tabulated, summed (x + y) + z as Eigen's squaredNorm sums cut_band_depth's (tests/fast/
// cut_set_test.cc pins both against the reference).
//
// The material. The reference (sd(tooth, g, 2 rho), reference/tooth/sdf.cc): for g in a solid
// voxel's cell (sdf_detail::voxel_of), that voxel; else the solid voxel v* minimising (D(v), v)
// over the solid voxels with D < (2 rho)^2 (sdf_nearer: the smallest distance, then the smallest
// flat index; D by box_distance2, the same double as the ball test's). The twin: the same inside
// test and voxel; outside, the same minimum over the exposed voxels of the ball with D < (2 rho)^2,
// certified when one exists and g is not near a grid plane: |g_a - p| >= eps on every axis a for
// every plane p = origin_a + h i (as computed), eps = 2^-23 R', R' = max(R, 2 rho); otherwise the
// provider's query (counted: fallbacks()). The constructor checks h >= eps and eps >= 2^-44
// (|origin|_inf + N h + R') (else every query falls back; both hold by orders of magnitude for a
// tooth). Claim: certified, the two agree.
// Proof: the found voxel b has D(b) < (2 rho)^2, so v* exists with D(v*) <= D(b) < R^2: v* is in
// the ball. If v* is exposed, it is among the voxels the twin minimised over (a subset of the
// reference's holding its minimiser): b = v*. Suppose v* is not exposed: its six face neighbours
// are solid. If D(v*) = 0, every term is 0, so g is in v*'s closed box (a gap whose square
// underflows is < eps), at least eps from its planes: then voxel_of, whose rounding is far below
// eps, puts g in v*'s cell, the inside case. So some term of v*, on axis a, is > 0: g is outside
// v*'s slab there. The face neighbour u toward g differs from v* in that term only, no larger
// (the same rounded bounds, monotone rounding): D(u) <= D(v*). If u = v* - e_a, its index is
// smaller and v* would not be the minimiser; so u = v* + e_a, g_a > hi_a(v*) and D(u) = D(v*).
// v*'s term is s^2, s = g_a - hi_a(v*) >= eps; u's is 0 if g_a <= hi_a(u), else (s - h)^2, smaller
// by more than h^2 >= eps^2. Each of D(u), D(v*) < R'^2 is within 2^-52 R'^2 of the exact sum of
// its terms (two roundings of at most 2^-53 each), and the terms differ by >= eps^2 = 2^-46 R'^2 >
// 2^-51 R'^2: D(u) < D(v*), a contradiction. So v* is exposed and b = v*.
//
// The material alone (stop 47: the field model's servo asks for it without a cut set, its cut being
// the worker's). The same minimum of (D(v), v) over the exposed voxels with D < min(R^2,
// (2 rho)^2), found nearest first instead of by the pass over the ball's band (N^2 voxels), by the
// walk the sdf model's local query uses too (fast/tooth/nearest_voxel_walk.h, stop 48): the last
// answer's voxel, if still exposed and within reach, bounds best = D from the start (the contact
// moves little from tick to tick); the walk lists the bricks within sqrt(best) (every voxel with
// D <= best has each axis term <= best), reads them nearest first, and a brick, a word or a 2^3
// block (its box shrunk to its set bits) only if its bound is < best, or = best once a voxel is
// found (a tie with a smaller index); best falls as nearer voxels come. No skipped block can hold
// the minimiser, so the answer is collect's with a cut set (the same certificate and fallback),
// whatever the seed; the cost is that of the blocks about the ball of radius D(v*): the surface
// within a block's size of it (a cap on an open surface; in a cavity about g, the bur's own hole,
// its whole wall). A span wider than the walk's arrays (voxel_walk::kMaxSpan bricks: a reach of
// ~90 voxels) returns false: the reference answers.
//
// The material without its voxel (stop 49; fast/tooth/material_blocks.h). The provider needs only
// the voxel's material, which material() finds without the voxel where the tooth's materials are
// uniform about g: from a voxel s still solid within 2 rho (the last answer's, or a voxel behind it
// when drilling took it), if every block of the material pyramid that may hold a solid voxel at
// least as near as s holds only s's material, that is the reference's voxel's material (proof in
// material_blocks.h), or, where the pyramid names a witness of another material nearer than s,
// again from it (collide50); else the nearest-first walk (material_alone) finds the voxel. The
// cost is then the pyramid's blocks about the ball of radius sqrt(D(s)) from the level of its
// size down, not the exposed voxels of the cavity's wall within a block of that sphere (~N^2).
//
// Real-time: collect(), material() and update() neither allocate nor throw (their buffers are
// sized by the constructor from the tip's radius and the grid).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "fast/tooth/material_blocks.h"
#include "reference/tooth/tooth_contacts.h"

namespace dentsim::fast {

// The tooth's exposed voxels as bits (header comment).
class SurfaceVoxels {
 public:
  static constexpr int kBrick = 8;  // brick edge [voxels]
  static constexpr int kWords = 8;  // 64-bit words of a brick

  // Reads tooth.codes (allocates: the slot index and a brick's room for every slot holding a
  // solid voxel).
  explicit SurfaceVoxels(const VoxelTooth& tooth);

  // After drilling removed the voxels `removed` of `tooth` (flat indices; drill_tick re-encoded
  // them and their face neighbours): their bits and their face neighbours' from tooth.codes.
  // Returns false, and current() is false from then on, if a bit had no brick's room (impossible
  // while the tooth only loses voxels). No allocation.
  bool update(const VoxelTooth& tooth, std::span<const std::size_t> removed);
  // Removes the voxels `removed` (flat indices) from `tooth` (the octree, the codes) and updates
  // the bits: the state FullOctree::remove_voxel and reencode_local for each, then update(),
  // leave, from the codes already held (the tooth's codes are those of its grid): the voxel's code
  // becomes 0 and its bit clear, each solid face neighbour's code gains the face toward it and its
  // bit is set; an empty voxel is skipped (nothing changes). 6 grid reads per voxel instead of 49,
  // and no neighbour read twice. Same return as update(). No allocation.
  bool remove(VoxelTooth& tooth, std::span<const std::size_t> removed);
  // Slot s's 8 words become `words` (as brick() gives them; null: all clear), taking a brick from
  // the reserve if it has none and a bit is set. Same return as update(). No allocation.
  bool replace(std::size_t s, const std::uint64_t* words);
  bool current() const { return current_; }

  bool exposed(int i, int j, int k) const;
  std::size_t count() const;  // voxels exposed (tests: count_surface_voxels)
  std::size_t brick_count() const { return bits_.size() / kWords; }
  std::size_t reserved_bricks() const { return bits_.capacity() / kWords; }
  int slots_per_axis() const { return nb_; }
  std::size_t slot(int bx, int by, int bz) const {
    return static_cast<std::size_t>(bx) +
           static_cast<std::size_t>(nb_) *
               (static_cast<std::size_t>(by) + static_cast<std::size_t>(nb_) * bz);
  }
  // The 8 words of slot s's brick, null if the slot has none (no exposed voxel yet).
  const std::uint64_t* brick(std::size_t s) const {
    const std::int32_t id = index_[s];
    return id < 0 ? nullptr : &bits_[static_cast<std::size_t>(id) * kWords];
  }
  // The bit of local voxel (x, y, z) of a brick (each in 0..7): the Morton interleave.
  static int local_bit(int x, int y, int z) {
    constexpr int kSpread[8] = {0, 1, 8, 9, 64, 65, 72, 73};  // bits 0, 1, 2 to 0, 3, 6
    return kSpread[x] | (kSpread[y] << 1) | (kSpread[z] << 2);
  }

 private:
  // Sets voxel (i, j, k)'s bit to `on`; false when it needs a brick where none may be taken.
  bool set(int i, int j, int k, bool on);

  static constexpr std::int32_t kNone = -1;    // no brick yet (room reserved)
  static constexpr std::int32_t kNoRoom = -2;  // no solid voxel at construction
  int n_ = 0, nb_ = 0;
  bool current_ = true;
  std::vector<std::int32_t> index_;   // per slot: brick id, kNone or kNoRoom
  std::vector<std::uint64_t> bits_;   // brick id * 8 + word; capacity: the reserve
};

// The 8^3 bricks a batch of removals changed on one tooth (the field worker's, fast/tooth/field.h),
// copied so that another tooth in the state the first had before the batch (the servo's) takes the
// state that removing the same voxels one by one (SurfaceVoxels::remove) leaves, by copying them
// back: no code, bit or mask is re-derived on the second tooth (issue #30, stop 49). A removal
// changes the voxel's code and bit and those of its six face neighbours (neighbors.h), and in the
// octree the voxel and the masks of its ancestors only: so the bricks holding a removed voxel or a
// face neighbour of one (the brick slots of SparseNeighborCodes and SurfaceVoxels, the same
// numbering) hold every changed code and bit, and the octree nodes of the bricks holding a removed
// voxel (FullOctree::save_node at the bricks' level: the brick's voxels, its subtree's masks and
// its ancestors') every changed voxel and mask. Every other byte of the two teeth was equal before
// and is untouched by both, so after apply() the two are equal byte for byte (codes by slot, bits
// by slot, voxels, masks; tests/fast/field_test.cc).
class ToothBricks {
 public:
  ToothBricks() = default;
  // Room for `capacity` bricks of `tooth` (allocates; the storage is written only as it is used).
  void reserve(const VoxelTooth& tooth, std::size_t capacity);
  // After `removed` was removed from `tooth` (its codes re-encoded) and `surface` updated: copies
  // the bricks (class comment). `marks`: one byte per brick slot (SurfaceVoxels::slot), all 0
  // (left so). Returns false, holding no brick (fits() false), when they are more than
  // capacity(). No allocation.
  bool take(const VoxelTooth& tooth, const SurfaceVoxels& surface,
            std::span<const std::size_t> removed, std::span<std::uint8_t> marks);
  // Copies them into `tooth` and `surface`, in the state take()'s had before the removal. Returns
  // false if a code or bit brick could not be taken there (impossible while the tooth only loses
  // voxels: the reserves are the same). No allocation.
  bool apply(VoxelTooth& tooth, SurfaceVoxels& surface) const;
  bool fits() const { return fits_; }
  std::size_t size() const { return count_; }
  std::size_t capacity() const { return capacity_; }

 private:
  struct Entry {
    std::uint32_t slot = 0;
    bool codes = false, bits = false;  // whether the slot had a brick of codes, of bits
    bool node = false;                 // whether it held a removed voxel (its node copied)
    // Its voxels' rows (j, k) holding a removed voxel, bit j + 8 k: the only rows of the node's
    // voxels the removal changed (the rest equal on both teeth), the only ones apply() copies.
    std::uint64_t rows = 0;
  };
  // Slot s's brick coordinates, its octree node's at level_ (a grid below 8^3: the root).
  std::array<int, 3> brick_of(std::size_t s) const {
    return {static_cast<int>(s % per_axis_), static_cast<int>((s / per_axis_) % per_axis_),
            static_cast<int>(s / (per_axis_ * per_axis_))};
  }

  int level_ = 0;              // the bricks' octree level: max(L - 3, 0)
  std::size_t per_axis_ = 0;   // brick slots per axis
  std::size_t node_bytes_ = 0;
  std::size_t capacity_ = 0, count_ = 0;
  bool fits_ = true;
  std::unique_ptr<Entry[]> entries_;
  std::unique_ptr<std::uint8_t[]> codes_;   // 512 per entry
  std::unique_ptr<std::uint64_t[]> bits_;   // SurfaceVoxels::kWords per entry
  std::unique_ptr<std::uint8_t[]> nodes_;   // node_bytes_ per entry
};

// The cut set and the material of the surface-proxy contact at g (header comment) for a tip of
// radius rho on `tooth` (which must outlive it; its changes reported to update()).
class SurfaceCutSet {
 public:
  // The voxel the material is read from (sd(tooth, g, 2 rho)'s found and voxel).
  struct Nearest {
    bool found = false;
    std::size_t voxel = 0;
  };

  // `sd`: the provider's signed-distance query (the material's uncertified case). Allocates.
  // Without `material_pyramid` no MaterialBlocks is built (~n^3 / 56 bytes and a pass over the
  // grid): material() then always walks (the field edit worker's, which never asks it).
  SurfaceCutSet(const VoxelTooth& tooth, double rho, SignedDistanceFn sd,
                bool material_pyramid = true);

  // drill_tick removed `removed` from the tooth.
  void update(std::span<const std::size_t> removed) { surface_.update(tooth_, removed); }
  // Removes `removed` from the tooth (this one's, given writable) and the bits: SurfaceVoxels::
  // remove.
  void remove(VoxelTooth& tooth, std::span<const std::size_t> removed) {
    surface_.remove(tooth, removed);
  }
  // The same removal as copies of another tooth's bricks (ToothBricks::apply).
  void replace(VoxelTooth& tooth, const ToothBricks& bricks) { bricks.apply(tooth, surface_); }

  // The nearest voxel into *nearest and, if `shares` is not null, collect_cut_set(tooth, contact,
  // g, rho, ...)'s members appended to `shares` and `voxels`. Returns false, touching nothing,
  // when it cannot answer (g not finite, or the bits not current): the caller asks the
  // reference. No allocation, no throw.
  bool collect(const Vec3& g, const Contact& contact, std::vector<Contact>* shares,
               std::vector<std::size_t>* voxels, Nearest* nearest);

  // The material of the solid voxel nearest to g within 2 rho (proxy_material's; kEmpty if none)
  // into *material, without the voxel where the material pyramid certifies it (header comment,
  // "The material without its voxel"), else by collect(g, .., nullptr, ..). Returns false,
  // touching nothing, where collect would. No allocation, no throw.
  bool material(const Vec3& g, std::uint8_t* material);

  const SurfaceVoxels& surface() const { return surface_; }
  const MaterialBlocks& material_blocks() const { return blocks_; }
  // material() queries the pyramid answered (tests and benchmarks).
  long certified() const { return certified_; }
  // Material queries answered by sd (no exposed voxel within reach, or g near a grid plane), and
  // all of them (tests and benchmarks).
  long fallbacks() const { return fallbacks_; }
  long queries() const { return queries_; }
  // Material-alone queries that started from the last answer's voxel (tests).
  long seeded() const { return seeded_queries_; }
  // The pyramid's refusals that named a witness material() asked again from (tests).
  long reseeded() const { return reseeded_; }
  // material() answers the held certificate gave without reading the pyramid (tests).
  long held() const { return held_hits_; }

 private:
  // A brick of the box: its slot and its place in the box (brick coordinates less the box's low
  // corner).
  struct BoxBrick {
    std::uint32_t slot;
    std::uint8_t x, y, z;
  };
  // The bricks of box [b_lo, b_hi] (brick coordinates) in decreasing Morton code, into order_
  // (kept while the box is the same).
  void order_bricks(const int b_lo[3], const int b_hi[3]);
  // Whether g lies within eps_ of a grid plane on some axis (header comment).
  bool near_grid_plane(const Vec3& g) const;
  // The box of voxels of the ball (g, r), a voxel of margin each side, clipped to the grid, and
  // its bricks: 0, 1 if it misses the grid, -1 if wider than the tables.
  int box_about(const Vec3& g, double r, int lo[3], int hi[3], int b_lo[3], int b_hi[3]) const;
  // The tables below for the box (collect's pass).
  void fill_tables(const Vec3& g, const int lo[3], const int hi[3], const int b_lo[3],
                   const int b_hi[3]);
  // The material alone, nearest first (header comment, "The material alone").
  bool material_alone(const Vec3& g, Nearest* nearest);
  // The material outside g's voxel: the found exposed voxel if certified, else sd (the seed).
  bool answer(const Vec3& g, bool found, std::size_t best, Nearest* nearest);
  // material()'s certificate outside g's voxel: from the seed (or the first solid voxel behind it,
  // away from g), true with *material if the pyramid holds only its material about g.
  bool certified_material(const Vec3& g, std::uint8_t* material);

  const VoxelTooth& tooth_;
  double rho_;
  SignedDistanceFn sd_;
  SurfaceVoxels surface_;
  double eps_ = 0.0;
  bool certify_ = true;  // the constructor's conditions (header comment)
  // Per axis, over the voxels of the box's bricks (from 8 b_lo): the squared gap of each voxel
  // to g (sphere_intersects_cells's term; +inf outside the ball's box), the squared offset of its
  // centre from g (cut_band_depth's term), and the least gap term of each aligned run of 2, 4 and
  // 8 voxels (a 2^3 block's, a word's and a brick's bound: collect's culls).
  std::vector<double> terms_[3], centre_[3], least2_[3], least4_[3], least8_[3];
  int bricks_across_ = 0;  // the box's bricks per axis at most (the tables' room / 8)
  std::vector<BoxBrick> order_;      // the box's bricks, decreasing Morton code
  std::vector<std::uint64_t> keys_;  // scratch of order_bricks
  int box_lo_[3] = {1, 1, 1}, box_hi_[3] = {0, 0, 0};  // the box order_ holds (empty)
  long fallbacks_ = 0, queries_ = 0;
  bool seeded_ = false;    // seed_ holds the last material query's voxel outside g's
  std::size_t seed_ = 0;
  long seeded_queries_ = 0;
  bool pyramid_ = true;    // blocks_ built (the constructor's flag)
  MaterialBlocks blocks_;  // the tooth's materials at construction
  long certified_ = 0, reseeded_ = 0;
  // The held certificate (servo51; certified_material): the pyramid passed material held_m_ for
  // the ball about held_x_ of squared radius held_r_ + kHeldMargin, squared (no voxel solid then,
  // hence none now, of another material has its box within that of held_x_).
  bool held_ = false;
  Vec3 held_x_ = Vec3::Zero();
  double held_r_ = 0.0;
  std::uint8_t held_m_ = 0;
  long held_hits_ = 0;
};

// dentsim::ToothContactProvider with its voxel side replaced by SurfaceCutSet: the fast
// pipeline's sdf (fast/tooth/tooth_contacts.h) and field (fast/tooth/field.h) providers derive
// from it. Same arguments and results as the reference provider.
class CutSetProvider : public dentsim::ToothContactProvider {
 public:
  CutSetProvider(VoxelTooth& tooth, ToolTip tip, double k_tooth, double b_tooth,
                 const DrillParams* drill, ContactModel model, SignedDistanceFn sd,
                 SampledField* field = nullptr);
  // The reference's drill(), then the removed voxels into the surface bits.
  int drill(std::span<const Contact> contacts, double T) override;
  const SurfaceCutSet& cut_set() const { return cut_; }

 protected:
  void surface_contact_voxels(const Vec3& g, Contact* contact, std::vector<Contact>* shares,
                              std::vector<std::size_t>* voxels) override;
  // The tooth lost `removed` outside drill() (the field model's late drilling, fast/tooth/field.h).
  void surface_removed(std::span<const std::size_t> removed) { cut_.update(removed); }
  // Removes `removed` from `tooth` (the provider's) and the bits at once (SurfaceVoxels::remove).
  void remove_voxels(VoxelTooth& tooth, std::span<const std::size_t> removed) {
    cut_.remove(tooth, removed);
  }
  // The same from the bricks another tooth's removal changed (ToothBricks::apply).
  void replace_bricks(VoxelTooth& tooth, const ToothBricks& bricks) { cut_.replace(tooth, bricks); }

 private:
  SurfaceCutSet cut_;
};

}  // namespace dentsim::fast
