// The fast surface-proxy contact's voxel side (fast/tooth/cut_set.h) against the reference
// (ToothContactProvider::surface_contact_voxels: collect_cut_set and proxy_material, reference/
// tooth/drilling.h and sdf.h) and a brute-force oracle:
// - the surface bits: set exactly on the voxels with a non-zero neighbour code, at construction and
//   after removals (update, 7 bits per removed voxel);
// - random anchors g near the surface of the procedural molar (64^3 to 256^3) and of a real molar
//   mesh (../shared/data), some on grid planes, some inside: the cut set (voxels, order, weights,
//   bitwise) equal to collect_cut_set's and to a brute force over the flat grid (every exposed
//   solid voxel of the ball with a band depth > 0, in the reference query's order written out:
//   decreasing Morton code of the 2^3 block, then the child index), and the material's voxel equal
//   to sd(tooth, g, 2 rho)'s and to the brute-force nearest solid voxel (smallest distance, then
//   smallest index);
// - the providers: the reference and the fast sdf and field providers (field stride 1 and 2) driven
//   along the same scripted bur path at four resolutions (h = 0.25 mm to 0.0425 mm, the last the
//   512^3 molar's voxel on a small block): every tick's contact, cut set and removed voxels
//   bitwise equal, the grids equal at the end, the surface bits still the codes, no allocation;
// - the drill scene's closed loop in the fast pipeline (sdf and field), its tooth's voxel side the
//   fast one or the reference's: every tick's contact wrench, torques and removed voxels bitwise
//   equal, and the removed volume.
// Bitwise because the arithmetic is the same (docs/tolerance_policy.md item 9).
#include "fast/tooth/cut_set.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "fast/tooth/field.h"
#include "fast/tooth/sdf.h"
#include "fast/tooth/tooth_contacts.h"
#include "reference/tooth/drilling.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/shared_meshes.h"
#include "tests/tooth/field_shapes.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/voxelize.h"

namespace dentsim {
namespace {

constexpr double kK = 3000.0, kB = 5.0, kT = 1e-3;

bool same(const Contact& a, const Contact& b) {
  return a.n == b.n && a.x_o == b.x_o && a.r == b.r && a.depth == b.depth &&
         a.stiffness == b.stiffness && a.damping == b.damping && a.weight == b.weight &&
         a.material == b.material;
}

// The first member where two cut sets differ (-1: equal), comparing voxels and contacts bitwise.
long first_difference(const std::vector<Contact>& a, const std::vector<std::size_t>& va,
                      const std::vector<Contact>& b, const std::vector<std::size_t>& vb) {
  const std::size_t n = std::min(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (va[i] != vb[i] || !same(a[i], b[i])) return static_cast<long>(i);
  }
  return a.size() == b.size() && va.size() == vb.size() ? -1 : static_cast<long>(n);
}

// ---- The brute-force oracle -------------------------------------------------------------------

// The Morton code of voxel (i, j, k) (x in bit 0, y in bit 1, z in bit 2, ...).
std::uint64_t morton(int i, int j, int k) {
  std::uint64_t m = 0;
  for (int b = 0; b < 10; ++b) {
    m |= static_cast<std::uint64_t>((i >> b) & 1) << (3 * b);
    m |= static_cast<std::uint64_t>((j >> b) & 1) << (3 * b + 1);
    m |= static_cast<std::uint64_t>((k >> b) & 1) << (3 * b + 2);
  }
  return m;
}

struct Oracle {
  std::vector<std::size_t> voxels;  // the cut set's voxels in the reference's order
  std::vector<double> weights;      // their band depths
  bool found = false;               // the material's voxel (sd's found, voxel)
  std::size_t voxel = 0;
};

// Every voxel of the box about g that a ball of radius max(R, 2 rho) can reach (two voxels of
// margin), tested one by one on the flat grid.
Oracle brute_force(const VoxelTooth& tooth, const Vec3& g, double rho, std::size_t capacity) {
  const VoxelGrid& grid = tooth.grid();
  const double h = grid.voxel_size;
  const CutBand cut = cut_band(rho);
  const double reach = proxy_material_reach(rho);
  const double wide = std::max(cut.reach, reach);
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, static_cast<int>(std::floor((g[a] - wide - grid.origin[a]) / h)) - 2);
    hi[a] = std::min(grid.n - 1, static_cast<int>(std::floor((g[a] + wide - grid.origin[a]) / h)) + 2);
  }
  // (block Morton code, child, voxel, depth), sorted by decreasing block, increasing child.
  std::vector<std::tuple<std::uint64_t, int, std::size_t, double>> members;
  Oracle o;
  double best2 = reach * reach;
  for (int k = lo[2]; k <= hi[2]; ++k) {
    for (int j = lo[1]; j <= hi[1]; ++j) {
      for (int i = lo[0]; i <= hi[0]; ++i) {
        if (!grid.solid(i, j, k)) continue;
        const std::size_t v = grid.index(i, j, k);
        const int ilo[3] = {i, j, k}, ihi[3] = {i + 1, j + 1, k + 1};
        const double d2 = sdf_detail::box_distance2(grid, ilo, ihi, g, nullptr);
        if (d2 < best2 || (o.found && d2 == best2 && v < o.voxel)) {
          best2 = d2;
          o.voxel = v;
          o.found = true;
        }
        if (!sphere_intersects_voxel(grid, i, j, k, g, cut.reach)) continue;
        if (exposed_faces(grid, i, j, k) == 0) continue;
        const double depth = cut_band_depth(grid, i, j, k, g, rho, cut.depth);
        if (!(depth > 0.0)) continue;
        const std::uint64_t m = morton(i, j, k);
        members.emplace_back(m >> 3, static_cast<int>(m & 7), v, depth);
      }
    }
  }
  std::sort(members.begin(), members.end(), [](const auto& a, const auto& b) {
    if (std::get<0>(a) != std::get<0>(b)) return std::get<0>(a) > std::get<0>(b);
    return std::get<1>(a) < std::get<1>(b);
  });
  for (const auto& m : members) {
    if (o.voxels.size() >= capacity) break;
    o.voxels.push_back(std::get<2>(m));
    o.weights.push_back(std::get<3>(m));
  }
  int cell[3];
  if (sdf_detail::voxel_of(grid, g, cell) && grid.solid(cell[0], cell[1], cell[2])) {
    o.found = true;  // signed_distance's inside case: the voxel holding g
    o.voxel = grid.index(cell[0], cell[1], cell[2]);
  }
  return o;
}

// ---- The surface bits ---------------------------------------------------------------------------

// How many voxels' bits differ from "the neighbour code is non-zero".
long bits_differing(const fast::SurfaceVoxels& s, const VoxelTooth& tooth) {
  const VoxelGrid& g = tooth.grid();
  long differ = 0;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        differ += s.exposed(i, j, k) != (tooth.codes.code(g.index(i, j, k)) != 0);
      }
    }
  }
  return differ;
}

TEST(SurfaceVoxels, AreTheVoxelsWithANonZeroCodeBeforeAndAfterRemovals) {
  VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, 64));
  fast::SurfaceVoxels s(tooth);
  const VoxelGrid& g = tooth.grid();
  EXPECT_EQ(s.count(), count_surface_voxels(g));
  EXPECT_EQ(bits_differing(s, tooth), 0);
  EXPECT_LE(s.brick_count(), s.reserved_bricks());
  // Remove random exposed voxels in batches as drill_tick does (octree, then the local codes),
  // reporting each batch; the bits follow at every batch.
  std::mt19937_64 rng(45);
  std::vector<std::size_t> surface;
  for (std::size_t v = 0; v < g.voxels.size(); ++v) {
    if (tooth.codes.code(v) != 0) surface.push_back(v);
  }
  std::shuffle(surface.begin(), surface.end(), rng);
  const std::size_t n = static_cast<std::size_t>(g.n);
  std::size_t next = 0;
  long removed = 0;
  for (int batch = 0; batch < 40; ++batch) {
    std::vector<std::size_t> gone;
    for (int r = 0; r < 200 && next < surface.size(); ++r, ++next) {
      const std::size_t v = surface[next];
      const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
      const int k = static_cast<int>(v / (n * n));
      if (tooth.octree.remove_voxel(i, j, k) == kEmpty) continue;
      reencode_local(tooth.octree.grid(), i, j, k, &tooth.codes);
      gone.push_back(v);
    }
    removed += static_cast<long>(gone.size());
    {
      testing::AllocationScope scope;
      EXPECT_TRUE(s.update(tooth, gone));
      EXPECT_EQ(scope.count(), 0);
    }
    ASSERT_EQ(bits_differing(s, tooth), 0) << "batch " << batch;
  }
  EXPECT_EQ(s.count(), count_surface_voxels(g));
  EXPECT_TRUE(s.current());
  std::printf("%ld voxels removed; %zu exposed, %zu bricks of %zu reserved\n", removed, s.count(),
              s.brick_count(), s.reserved_bricks());
  EXPECT_GT(removed, 4000);
}

// SurfaceVoxels::remove (the field model's replay of the worker's removal on the servo's tooth,
// stop 47) leaves the octree, the codes and the bits as remove_voxel and reencode_local for each
// voxel, then update(), do: random batches of exposed voxels of the molar, some batches repeating
// voxels already removed, some removing face neighbours in the same batch; the grids, every
// octree node, every code and every bit equal after each batch, no allocation.
TEST(SurfaceVoxels, RemoveLeavesTheToothAndBitsOfRemoveVoxelAndReencodeLocal) {
  const VoxelTooth start(voxelize_procedural_molar(MolarParams{}, 64));
  VoxelTooth ref = start, fst = start;
  fast::SurfaceVoxels s_ref(ref), s_fst(fst);
  const VoxelGrid& g = ref.grid();
  const std::size_t n = static_cast<std::size_t>(g.n);
  std::mt19937_64 rng(47);
  std::vector<std::size_t> done;
  long removed = 0;
  for (int batch = 0; batch < 30; ++batch) {
    std::vector<std::size_t> surface;
    for (std::size_t v = 0; v < g.voxels.size(); ++v) {
      if (ref.codes.code(v) != 0) surface.push_back(v);
    }
    std::shuffle(surface.begin(), surface.end(), rng);
    std::vector<std::size_t> batch_voxels;
    for (std::size_t r = 0; r < 60 && r < surface.size(); ++r) {
      batch_voxels.push_back(surface[r]);
      if (r % 5 == 0 && surface[r] % n + 1 < n) batch_voxels.push_back(surface[r] + 1);  // +x
    }
    if (batch % 3 == 2) batch_voxels.insert(batch_voxels.end(), done.begin(), done.begin() + 10);
    for (const std::size_t v : batch_voxels) {
      const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
      const int k = static_cast<int>(v / (n * n));
      removed += ref.octree.remove_voxel(i, j, k) != kEmpty;
      reencode_local(ref.octree.grid(), i, j, k, &ref.codes);
      done.push_back(v);
    }
    EXPECT_TRUE(s_ref.update(ref, batch_voxels));
    {
      testing::AllocationScope scope;
      EXPECT_TRUE(s_fst.remove(fst, batch_voxels));
      EXPECT_EQ(scope.count(), 0);
    }
    ASSERT_TRUE(fst.grid().voxels == g.voxels) << "batch " << batch;
    long differ = 0;
    for (std::size_t v = 0; v < g.voxels.size(); ++v) {
      differ += fst.codes.code(v) != ref.codes.code(v);
    }
    for (int l = 0; l < ref.octree.levels(); ++l) {
      const int side = 1 << l;
      for (int z = 0; z < side; ++z) {
        for (int y = 0; y < side; ++y) {
          for (int x = 0; x < side; ++x) {
            differ += fst.octree.occupied(l, x, y, z) != ref.octree.occupied(l, x, y, z);
          }
        }
      }
    }
    for (int k = 0; k < g.n; ++k) {
      for (int j = 0; j < g.n; ++j) {
        for (int i = 0; i < g.n; ++i) differ += s_fst.exposed(i, j, k) != s_ref.exposed(i, j, k);
      }
    }
    ASSERT_EQ(differ, 0) << "batch " << batch;
    ASSERT_EQ(bits_differing(s_fst, fst), 0) << "batch " << batch;
  }
  EXPECT_TRUE(s_fst.current());
  EXPECT_GT(removed, 1500);
}

// The Morton layout of a brick: word w is a 4^3 block, byte b of a word a 2^3 block, bit c of the
// byte the child c = dx + 2 dy + 4 dz (the octree's child index).
TEST(SurfaceVoxels, BricksAreInMortonOrder) {
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(0, 0, 0), 0);
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(1, 0, 0), 1);
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(0, 1, 0), 2);
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(0, 0, 1), 4);
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(2, 0, 0), 8);
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(0, 0, 4), 256);
  EXPECT_EQ(fast::SurfaceVoxels::local_bit(7, 7, 7), 511);
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x) {
        EXPECT_EQ(static_cast<std::uint64_t>(fast::SurfaceVoxels::local_bit(x, y, z)),
                  morton(x, y, z));
      }
    }
  }
}

// ---- Random anchors near a surface ------------------------------------------------------------

struct Agreement {
  long queries = 0, members = 0, inside = 0, planes = 0, mismatches = 0;
};

// One anchor: the twin, the reference and the oracle.
void compare_at(const VoxelTooth& tooth, fast::SurfaceCutSet& twin, const Vec3& g, double rho,
                Agreement* a) {
  Contact contact;  // the members copy it: any fields do
  contact.n = Vec3(0.6, 0.0, 0.8);
  contact.x_o = g - rho * contact.n;
  contact.depth = 1e-5;
  contact.stiffness = 3000.0;
  contact.damping = 5.0;
  std::vector<Contact> ref, fst;
  std::vector<std::size_t> ref_v, fst_v, candidates;
  ref.reserve(kContactCapacity);
  fst.reserve(kContactCapacity);
  ref_v.reserve(kContactCapacity);
  fst_v.reserve(kContactCapacity);
  collect_cut_set(tooth, contact, g, rho, &candidates, &ref, &ref_v);
  const SignedDistance sd = signed_distance(tooth, g, proxy_material_reach(rho));
  // The material alone (no drilling) first: its search starts from the previous anchor's answer
  // when that voxel is within reach (material_alone's seed), any seed giving the same voxel.
  fast::SurfaceCutSet::Nearest alone;
  ASSERT_TRUE(twin.collect(g, contact, nullptr, nullptr, &alone));
  fast::SurfaceCutSet::Nearest near;
  ASSERT_TRUE(twin.collect(g, contact, &fst, &fst_v, &near));
  const Oracle o = brute_force(tooth, g, rho, kContactCapacity);
  ++a->queries;
  a->members += static_cast<long>(ref.size());
  const long d = first_difference(ref, ref_v, fst, fst_v);
  bool oracle_ok = o.voxels == ref_v;
  for (std::size_t i = 0; oracle_ok && i < ref.size(); ++i) oracle_ok = o.weights[i] == ref[i].weight;
  const bool near_ok = near.found == sd.found && (!sd.found || near.voxel == sd.voxel) &&
                       alone.found == near.found && alone.voxel == near.voxel &&
                       o.found == sd.found && (!sd.found || o.voxel == sd.voxel);
  if (d >= 0 || !oracle_ok || !near_ok) {
    ++a->mismatches;
    ADD_FAILURE() << "g " << g.transpose() << ": " << ref.size() << " members (fast "
                  << fst.size() << ", oracle " << o.voxels.size() << "), first difference " << d
                  << ", oracle agrees " << oracle_ok << "; nearest " << sd.found << " "
                  << sd.voxel << " vs " << near.found << " " << near.voxel << " (oracle "
                  << o.found << " " << o.voxel << ")";
  }
}

// Anchors near the surface of `tooth`: at a random exposed voxel's centre plus up to 2.2 rho in a
// random direction; one in 8 moved onto a grid plane (exactly, or a few ulps off) on one axis; one
// in 16 at a random point of a solid voxel.
Agreement random_anchors(const VoxelTooth& tooth, double rho, int count, std::uint64_t seed) {
  const VoxelGrid& grid = tooth.grid();
  std::vector<std::size_t> surface;
  for (std::size_t v = 0; v < grid.voxels.size(); ++v) {
    if (tooth.codes.code(v) != 0) surface.push_back(v);
  }
  fast::SurfaceCutSet twin(tooth, rho, &signed_distance);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, surface.size() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), dist(0.0, 2.2 * rho), cell(0.0, 1.0);
  const std::size_t n = static_cast<std::size_t>(grid.n);
  Agreement a;
  for (int q = 0; q < count; ++q) {
    const std::size_t v = surface[pick(rng)];
    const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
    const int k = static_cast<int>(v / (n * n));
    Vec3 g;
    if (q % 16 == 15) {
      g = grid.origin + grid.voxel_size * Vec3(i + cell(rng), j + cell(rng), k + cell(rng));
      ++a.inside;
    } else {
      Vec3 d(unit(rng), unit(rng), unit(rng));
      if (d.norm() < 1e-3) d = Vec3::UnitZ();
      g = grid.center(i, j, k) + dist(rng) * d.normalized();
    }
    if (q % 8 == 3) {  // onto a plane origin + h i of one axis, or a few ulps from it
      const int axis = q % 3;
      const double p = grid.origin[axis] +
                       grid.voxel_size * std::floor((g[axis] - grid.origin[axis]) / grid.voxel_size);
      g[axis] = (q / 8) % 3 == 0 ? p : std::nextafter(p, (q / 8) % 3 == 1 ? 1.0 : -1.0);
      ++a.planes;
    }
    compare_at(tooth, twin, g, rho, &a);
    if (a.mismatches > 5) break;
  }
  std::printf("%dx: %ld anchors (%ld on a plane, %ld inside), %ld cut members, %ld material "
              "queries by sd of %ld\n",
              grid.n, a.queries, a.planes, a.inside, a.members, twin.fallbacks(), twin.queries());
  EXPECT_EQ(twin.queries(), 2 * a.queries);
  // The certificate answers all but the anchors on planes or with no exposed voxel in the ball.
  EXPECT_LT(twin.fallbacks(), twin.queries() / 2);
  return a;
}

TEST(SurfaceCutSet, EqualsTheReferenceAndBruteForceNearTheMolarsSurface) {
  const int resolutions[] = {64, 128, 256};
  for (const int n : resolutions) {
    const VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, n));
    const Agreement a = random_anchors(tooth, 0.5e-3, n == 256 ? 1000 : 2000, 30 + n);
    EXPECT_EQ(a.mismatches, 0) << n;
    EXPECT_GT(a.members, 10 * a.queries) << n;  // signal: most anchors cut something
  }
  // A bur wider than the band reaches (rho = 1 mm) and a narrow one (0.15 mm, rho / h < 1).
  const VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, 128));
  EXPECT_EQ(random_anchors(tooth, 1.0e-3, 600, 7).mismatches, 0);
  EXPECT_EQ(random_anchors(tooth, 0.15e-3, 600, 8).mismatches, 0);
}

TEST(SurfaceCutSet, EqualsTheReferenceAndBruteForceNearAMeshsSurface) {
  const std::unique_ptr<VoxelTooth> tooth = test::shared_molar_tooth(128);
  if (tooth == nullptr) GTEST_SKIP() << "absent: " << test::shared_data_path("molar-cc0.stl");
  const Agreement a = random_anchors(*tooth, 0.5e-3, 2000, 46);
  EXPECT_EQ(a.mismatches, 0);
  EXPECT_GT(a.members, 10 * a.queries);
}

// ---- The culls at bricks' corners and the grid's edges (stop 46) -------------------------------

// collect skips a brick, a word (4^3 block) or a 2^3 block whose least gap terms per axis, summed
// as a voxel's are, are not < R^2. Their bounds are tightest where the ball's box meets block
// boundaries and the grid's edges: anchors at bricks' corners (grid planes 8 i on every axis,
// exactly, an ulp either side, or a random fraction of a voxel off) and at the grid's faces, edges
// and corners (inside, on, and just outside the grid, where the box is clipped), on a tooth whose
// solid reaches the grid's faces (a wavy slab under z = f(x, y) across the whole grid, and a ball
// about the grid's top corner), with the molar's voxel at 64^3, 128^3 and 512^3 (the ball 4 to
// 32 voxels across; at 512^3's voxel the box spans 5 to 6 bricks): the cut set and the material
// equal to the reference's and to the brute force (compare_at).
VoxelGrid edge_grid(int n, double h) {
  const double side = n * h;
  return test::solid_grid(n, side, [side](const Vec3& p) {
    const double u = p.x() / side, v = p.y() / side;
    const double floor = side * (0.45 + 0.12 * std::sin(7.0 * u) * std::cos(5.0 * v));
    return p.z() < floor || (p - Vec3(side, side, side)).norm() < 0.3 * side;
  });
}

VoxelTooth edge_tooth(int n, double h) { return VoxelTooth(edge_grid(n, h)); }

TEST(SurfaceCutSet, EqualsTheReferenceAtBricksCornersAndTheGridsEdges) {
  const MolarParams molar;
  const double h128 = voxelize_procedural_molar(molar, 32).voxel_size * 32.0 / 128.0;
  const double rho = 0.5e-3;
  struct Case {
    int n;
    double h;
  };
  const Case cases[] = {{32, 2.0 * h128}, {64, 2.0 * h128}, {64, h128}, {64, 0.25 * h128}};
  for (const Case& c : cases) {
    SCOPED_TRACE("n " + std::to_string(c.n) + ", h " + std::to_string(c.h));
    const VoxelTooth tooth = edge_tooth(c.n, c.h);
    const VoxelGrid& grid = tooth.grid();
    std::vector<std::size_t> surface;
    for (std::size_t v = 0; v < grid.voxels.size(); ++v) {
      if (tooth.codes.code(v) != 0) surface.push_back(v);
    }
    ASSERT_FALSE(surface.empty());
    fast::SurfaceCutSet twin(tooth, rho, &signed_distance);
    std::mt19937_64 rng(46 + c.n);
    std::uniform_int_distribution<std::size_t> pick(0, surface.size() - 1);
    std::uniform_int_distribution<int> choice(0, 5);
    std::uniform_real_distribution<double> fraction(0.0, 1.0), unit(-1.0, 1.0);
    const double reach = cut_band(rho).reach;
    const std::size_t nn = static_cast<std::size_t>(grid.n);
    // Coordinate a of a grid plane (origin + h i, as the grid computes it), moved by `how`: 0 on
    // it, 1 and 2 an ulp either side, 3 a random fraction of a voxel either side, 4 and 5 a
    // random fraction of the band's reach either side.
    auto off_plane = [&](int a, int i, int how) {
      const double p = grid.origin[a] + grid.voxel_size * i;
      switch (how) {
        case 0: return p;
        case 1: return std::nextafter(p, 1.0);
        case 2: return std::nextafter(p, -1.0);
        case 3: return p + unit(rng) * grid.voxel_size;
        default: return p + (how == 4 ? 1.0 : -1.0) * fraction(rng) * reach;
      }
    };
    Agreement a;
    for (int q = 0; q < 1500 && a.mismatches <= 5; ++q) {
      const std::size_t v = surface[pick(rng)];
      const int ijk[3] = {static_cast<int>(v % nn), static_cast<int>((v / nn) % nn),
                          static_cast<int>(v / (nn * nn))};
      Vec3 g;
      if (q % 2 == 0) {  // the brick corner nearest to a surface voxel
        for (int ax = 0; ax < 3; ++ax) {
          const int corner = 8 * static_cast<int>(std::lround(ijk[ax] / 8.0));
          g[ax] = off_plane(ax, corner, choice(rng));
        }
      } else {  // a surface voxel's centre, x or y or both onto the grid's faces (z too, 1 in 6)
        g = grid.center(ijk[0], ijk[1], ijk[2]);
        const int axes = 1 + (q / 2) % 3;  // x, y or both
        for (int ax = 0; ax < 3; ++ax) {
          const bool snap = ax < 2 ? ((axes >> ax) & 1) != 0 : (q / 2) % 6 == 5;
          if (snap) g[ax] = off_plane(ax, fraction(rng) < 0.5 ? 0 : grid.n, choice(rng));
        }
      }
      compare_at(tooth, twin, g, rho, &a);
    }
    std::printf("n %d, h %.4g mm: %ld anchors, %ld cut members, %ld material queries by sd of %ld\n",
                grid.n, 1e3 * grid.voxel_size, a.queries, a.members, twin.fallbacks(),
                twin.queries());
    EXPECT_EQ(a.mismatches, 0);
    EXPECT_GT(a.members, 3 * a.queries);  // signal: most anchors cut something
  }
}

// ---- The material alone, nearest first (stop 47) -----------------------------------------------

// collect without a cut set searches nearest first from the last answer's voxel (the seed) and
// reads only the blocks whose bound can hold a voxel as near (cut_set.h "The material alone").
// Walks of small steps (up to 1.5 voxels, so the seed is mostly valid but often not the nearest)
// held 0.7 to 1.2 rho off the last answer's voxel (as the proxy's anchor is); every third step one
// coordinate moved onto the nearest voxel's, brick's (8 i, within 1.5 voxels) or grid face's
// plane, exactly or an ulp either side; every 16th a jump of up to 2.2 rho (the seed out of reach,
// or far from the nearest); every 10th the removal of the answer's voxel and some of its
// neighbours as drill_tick removes them (the seed gone or no longer exposed). At every step the
// voxel equals sd(tooth, g, 2 rho)'s and the brute force's, with no allocation; the seed is used
// in a third of the steps at least. Last, anchors on an exact lattice, where the nearest voxel is
// often a tie.
struct Walks {
  long steps = 0, seeded = 0, removed = 0, mismatches = 0;
  long certified = 0;  // material() answers the pyramid gave (a second twin, stop 49)
  long reseeded = 0;   // its refusals that named a witness it asked again from (collide50)
  long held = 0;       // its answers from the held certificate (servo51)
};

// `pyramid`: the second twin's constructor flag (false: no MaterialBlocks, material() walks).
Walks material_walks(VoxelTooth& tooth, double rho, int walks, int steps, std::uint64_t seed,
                     bool lattice = false, bool pyramid = true) {
  const VoxelGrid& grid = tooth.grid();
  fast::SurfaceCutSet twin(tooth, rho, &signed_distance);
  // The material without its voxel (material(), stop 49) along the same walk, on its own twin
  // (its seed moves its own way).
  fast::SurfaceCutSet blocks(tooth, rho, &signed_distance, pyramid);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), fraction(0.0, 1.0);
  const std::size_t nn = static_cast<std::size_t>(grid.n);
  const double h = grid.voxel_size;
  Contact contact;
  contact.stiffness = kK;
  contact.damping = kB;
  Walks w;
  auto direction = [&] {
    Vec3 d(unit(rng), unit(rng), unit(rng));
    return d.norm() < 1e-3 ? Vec3(Vec3::UnitZ()) : Vec3(d.normalized());
  };
  for (int walk = 0; walk < walks && w.mismatches <= 5; ++walk) {
    std::vector<std::size_t> surface;
    for (std::size_t v = 0; v < grid.voxels.size(); ++v) {
      if (tooth.codes.code(v) != 0) surface.push_back(v);
    }
    const std::size_t v0 = surface[std::uniform_int_distribution<std::size_t>(
        0, surface.size() - 1)(rng)];
    Vec3 g = grid.center(static_cast<int>(v0 % nn), static_cast<int>((v0 / nn) % nn),
                         static_cast<int>(v0 / (nn * nn))) +
             rho * direction();
    bool last_found = false;
    std::size_t last = 0;
    for (int s = 0; s < steps && w.mismatches <= 5; ++s) {
      if (s % 16 == 15) {
        g += 2.2 * rho * fraction(rng) * direction();
      } else if (last_found) {  // held 0.7 to 1.2 rho off the last answer's voxel, as a proxy is
        const Vec3 c = grid.center(static_cast<int>(last % nn), static_cast<int>((last / nn) % nn),
                                   static_cast<int>(last / (nn * nn)));
        const Vec3 off = (g - c).norm() > 1e-3 * h ? Vec3((g - c).normalized()) : direction();
        g = c + rho * (0.7 + 0.5 * fraction(rng)) * off + 1.5 * h * fraction(rng) * direction();
      } else {
        g += 1.5 * h * fraction(rng) * direction();
      }
      if (lattice) {  // onto the lattice of quarter voxels (grid origin 0, h a power of 2)
        for (int a = 0; a < 3; ++a) g[a] = 0.25 * h * std::round(g[a] / (0.25 * h));
      }
      if (s % 3 == 1) {  // onto a brick's plane or the grid's face on one axis
        const int a = (s / 3) % 3;
        const double u = (g[a] - grid.origin[a]) / h;
        // The nearest brick's plane within 1.5 voxels, else the grid's face within 2, else the
        // nearest voxel plane (a step stays small).
        const int brick = 8 * static_cast<int>(std::lround(u / 8.0));
        int plane = static_cast<int>(std::lround(u));
        if (std::abs(brick - u) < 1.5) plane = brick;
        if (u < 2.0) plane = 0;
        if (u > grid.n - 2.0) plane = grid.n;
        const double p = grid.origin[a] + h * plane;
        const int how = static_cast<int>(3.0 * fraction(rng));
        g[a] = how == 0 ? p : std::nextafter(p, how == 1 ? 1.0 : -1.0);
      }
      fast::SurfaceCutSet::Nearest alone;
      const long seeded_before = twin.seeded();
      std::uint8_t material = 0xee;
      {
        testing::AllocationScope scope;
        EXPECT_TRUE(twin.collect(g, contact, nullptr, nullptr, &alone));
        EXPECT_TRUE(blocks.material(g, &material));
        EXPECT_EQ(scope.count(), 0);
      }
      w.seeded += twin.seeded() - seeded_before;
      last_found = alone.found;
      last = alone.voxel;
      ++w.steps;
      const SignedDistance sd = signed_distance(tooth, g, proxy_material_reach(rho));
      const Oracle o = brute_force(tooth, g, rho, 0);
      const std::uint8_t want = proxy_material(tooth, g, rho);
      const bool ok = alone.found == sd.found && (!sd.found || alone.voxel == sd.voxel) &&
                      o.found == sd.found && (!sd.found || o.voxel == sd.voxel) &&
                      material == want;
      if (!ok) {
        ++w.mismatches;
        ADD_FAILURE() << "walk " << walk << " step " << s << " g " << g.transpose() << ": sd "
                      << sd.found << " " << sd.voxel << ", fast " << alone.found << " "
                      << alone.voxel << ", oracle " << o.found << " " << o.voxel << "; material "
                      << int{want} << ", without the voxel " << int{material};
      }
      if (s % 10 == 9 && alone.found) {  // drill the answer's voxel and some neighbours away
        std::vector<std::size_t> gone;
        const int c[3] = {static_cast<int>(alone.voxel % nn),
                          static_cast<int>((alone.voxel / nn) % nn),
                          static_cast<int>(alone.voxel / (nn * nn))};
        for (int d = 0; d < 7; ++d) {
          int u[3] = {c[0], c[1], c[2]};
          if (d > 0) u[face_axis(d - 1)] += face_sign(d - 1);
          if (d > 0 && fraction(rng) < 0.5) continue;
          if (!grid.inside(u[0], u[1], u[2])) continue;
          if (tooth.octree.remove_voxel(u[0], u[1], u[2]) == kEmpty) continue;
          reencode_local(tooth.octree.grid(), u[0], u[1], u[2], &tooth.codes);
          gone.push_back(grid.index(u[0], u[1], u[2]));
        }
        twin.update(gone);
        blocks.update(gone);
        w.removed += static_cast<long>(gone.size());
      }
    }
  }
  w.certified = blocks.certified();
  w.reseeded = blocks.reseeded();
  w.held = blocks.held();
  std::printf("%dx, h %.4g mm, rho %.3g mm: %ld steps, %ld seeded, %ld voxels removed, %ld "
              "material queries by sd of %ld; without the voxel %ld of %ld (%ld held)\n",
              grid.n, 1e3 * h, 1e3 * rho, w.steps, w.seeded, w.removed, twin.fallbacks(),
              twin.queries(), w.certified, blocks.queries(), w.held);
  return w;
}

TEST(SurfaceCutSet, TheMaterialAloneNearestFirstEqualsTheReferenceAlongWalks) {
  for (const int n : {64, 128}) {
    VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, n));
    const Walks w = material_walks(tooth, 0.5e-3, 40, 60, 470 + n);
    EXPECT_EQ(w.mismatches, 0) << n;
    EXPECT_GT(w.seeded, w.steps / 3) << n;  // signal: the seed is used
    EXPECT_GT(w.removed, 100) << n;
  }
  // A narrow bur (rho / h < 1) and a wide one on the 128^3 molar.
  for (const double rho : {0.15e-3, 1.0e-3}) {
    VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, 128));
    EXPECT_EQ(material_walks(tooth, rho, 20, 60, 480).mismatches, 0) << rho;
  }
  // The wavy slab reaching the grid's faces, with the 512^3 molar's voxel (the ball ~24 voxels
  // across) and with 128^3's.
  const double h128 = voxelize_procedural_molar(MolarParams{}, 32).voxel_size * 32.0 / 128.0;
  for (const double h : {0.25 * h128, h128}) {
    VoxelTooth tooth = edge_tooth(64, h);
    const Walks w = material_walks(tooth, 0.5e-3, 30, 60, 490);
    EXPECT_EQ(w.mismatches, 0) << h;
    EXPECT_GT(w.seeded, w.steps / 3) << h;
  }
  // Ties: with the grid's origin at 0, h a power of two and the anchors on the lattice of quarter
  // voxels, every gap and term is exact, so voxels either side of an anchor's mid-voxel plane have
  // the same D: the smaller index must win (a block whose bound equals the best is read).
  for (const int e : {12, 14}) {
    VoxelTooth tooth = edge_tooth(64, std::ldexp(1.0, -e));
    const Walks w = material_walks(tooth, 0.5e-3, 30, 60, 500 + e, true);
    EXPECT_EQ(w.mismatches, 0) << e;
    EXPECT_GT(w.seeded, w.steps / 3) << e;
  }
}

// ---- The material without its voxel (stop 49) ---------------------------------------------------

// The wavy slab's solid voxels repainted: 0 as is (enamel), 1 slabs 3 voxels thick across x
// (enamel, dentin), 2 one-voxel walls of dentin on brick planes (x = 8 i + 7, y = 8 j), 3 caries
// specks (1 voxel in 200), 4 an enamel shell `shell` voxels deep over dentin (z below the column's
// top, as a tooth's).
VoxelGrid painted(VoxelGrid grid, int pattern, int shell = 6) {
  const int n = grid.n;
  std::mt19937_64 rng(4900 + pattern);
  std::uniform_int_distribution<int> speck(0, 199);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      int depth = 0;  // solid voxels above in the column, from its top
      for (int k = n - 1; k >= 0; --k) {
        if (!grid.solid(i, j, k)) {
          depth = 0;
          continue;
        }
        Material m = kEnamel;
        switch (pattern) {
          case 1: m = (i / 3) % 2 == 1 ? kDentin : kEnamel; break;
          case 2: m = i % 8 == 7 || j % 8 == 0 ? kDentin : kEnamel; break;
          case 3: m = speck(rng) == 0 ? kCaries : kEnamel; break;
          case 4: m = depth >= shell ? kDentin : kEnamel; break;
          default: break;
        }
        grid.set(i, j, k, m);
        ++depth;
      }
    }
  }
  return grid;
}

// material() (the pyramid's certificate, else the nearest-first walk) along material_walks' walks
// (material_walks compares it at every step with proxy_material(tooth, g, rho), the reference,
// with no allocation, the answer's voxel and neighbours drilled away every tenth step) on the
// procedural molar (enamel, dentin, pulp, caries) at 64^3 and 128^3 and on the wavy slab painted
// with walls and layers crossing blocks (painted above), at 128^3's voxel and at 512^3's, and on
// the exact lattice (ties). The pyramid answers most queries where the materials are uniform and
// some where they are not; the walk the rest.
TEST(SurfaceCutSet, TheMaterialWithoutItsVoxelIsTheReferencesAlongWalks) {
  for (const int n : {64, 128}) {
    VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, n));
    const Walks w = material_walks(tooth, 0.5e-3, 30, 60, 4900 + n);
    EXPECT_EQ(w.mismatches, 0) << n;
    EXPECT_GT(w.certified, w.steps / 3) << n;  // signal: the pyramid answers
  }
  const double h128 = voxelize_procedural_molar(MolarParams{}, 32).voxel_size * 32.0 / 128.0;
  long reseeded = 0, held = 0;
  for (const double h : {0.25 * h128, h128}) {
    for (int pattern = 0; pattern <= 4; ++pattern) {
      VoxelTooth tooth(painted(edge_grid(64, h), pattern));
      const Walks w = material_walks(tooth, 0.5e-3, 12, 60, 4910 + pattern);
      EXPECT_EQ(w.mismatches, 0) << h << " pattern " << pattern;
      reseeded += w.reseeded;
      held += w.held;
      // Signal: the pyramid answers on a uniform tooth, and the walk where walls cross the ball.
      if (pattern == 0) {
        EXPECT_GT(w.certified, w.steps * 2 / 3) << h;
      } else if (pattern == 2) {
        EXPECT_LT(w.certified, w.steps * 9 / 10) << h;
      }
    }
  }
  // Signal: across the junctions the certificate is asked again from a witness (collide50).
  EXPECT_GT(reseeded, 20);
  EXPECT_GT(held, 100);  // signal: the held certificate answers, junctions included (servo51)
  for (const int e : {12, 14}) {
    for (const int pattern : {1, 2, 4}) {
      VoxelTooth tooth(painted(edge_grid(64, std::ldexp(1.0, -e)), pattern, 2));
      const Walks w = material_walks(tooth, 0.5e-3, 12, 60, 4920 + e, true);
      EXPECT_EQ(w.mismatches, 0) << e << " pattern " << pattern;
    }
  }
}

// The field edit worker's cut set builds no pyramid (collide50): material() is then the walk's,
// still the reference's along the walks, and never the pyramid's.
TEST(SurfaceCutSet, WithoutThePyramidTheMaterialIsTheWalksAndTheReferences) {
  VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, 64));
  const Walks w = material_walks(tooth, 0.5e-3, 12, 60, 5000, false, false);
  EXPECT_EQ(w.mismatches, 0);
  EXPECT_EQ(w.certified, 0);
  EXPECT_GT(w.steps, 600);
  const fast::SurfaceCutSet none(tooth, 0.5e-3, &signed_distance, false);
  EXPECT_EQ(none.material_blocks().levels(), 0);
}

// The pyramid's status: every block's, at every level, the one material of its solid voxels
// (kEmpty if none, kMixed if more), by brute force over random grids (8 to 32 voxels, sparse to
// dense, one to three materials) and the single-voxel grid.
TEST(MaterialBlocks, StatusIsEachBlocksMaterialsAtEveryLevel) {
  std::mt19937_64 rng(4930);
  std::uniform_real_distribution<double> fraction(0.0, 1.0);
  long mixed = 0, uniform = 0, empty = 0;
  for (const int n : {1, 2, 8, 16, 32}) {
    for (const double solid : {0.01, 0.5, 1.0}) {
      for (const int materials : {1, 3}) {
        VoxelGrid grid(n, Vec3(1e-3, -2e-3, 0.5e-3), 0.1e-3);
        for (std::uint8_t& v : grid.voxels) {
          if (!(fraction(rng) < solid)) continue;
          // Mostly enamel; with three materials, 1 in 10 dentin or pulp.
          v = materials == 1 || fraction(rng) < 0.9 ? kEnamel
              : fraction(rng) < 0.5                  ? kDentin
                                                     : kPulp;
        }
        const fast::MaterialBlocks blocks(grid);
        ASSERT_EQ(blocks.across(blocks.levels() - 1), 1);
        for (int l = 0; l < blocks.levels(); ++l) {
          const int e = blocks.edge(l);
          ASSERT_EQ(blocks.across(l) * e, n);
          for (int z = 0; z < blocks.across(l); ++z) {
            for (int y = 0; y < blocks.across(l); ++y) {
              for (int x = 0; x < blocks.across(l); ++x) {
                std::uint8_t want = kEmpty;
                for (int k = e * z; k < e * (z + 1); ++k) {
                  for (int j = e * y; j < e * (y + 1); ++j) {
                    for (int i = e * x; i < e * (x + 1); ++i) {
                      const std::uint8_t m = grid.at(i, j, k);
                      if (m == kEmpty || m == want) continue;
                      want = want == kEmpty ? m : fast::MaterialBlocks::kMixed;
                    }
                  }
                }
                ASSERT_EQ(blocks.status(l, x, y, z), want) << n << " level " << l;
                mixed += want == fast::MaterialBlocks::kMixed;
                uniform += want != kEmpty && want != fast::MaterialBlocks::kMixed;
                empty += want == kEmpty;
              }
            }
          }
        }
      }
    }
  }
  EXPECT_GT(mixed, 100);
  EXPECT_GT(uniform, 100);
  EXPECT_GT(empty, 100);
}

// only(grid, x, d2, m) is the certificate: when true, no voxel solid in the grid with D <= d2 at x
// has a material other than m (D by the reference's box_distance2). Asked at the very D of a solid
// voxel v (the tie: a block whose bound equals d2 may hold v) with m = v's material and with each
// other material (then it must refuse), at random points about the grid, on grid planes and nodes
// (where D ties between voxels) with the origin at 0 and h a power of two (exact gaps), on painted
// slabs (walls, specks, a shell); then again after random removals from the grid (the pyramid not
// rebuilt: a grid that only loses voxels). A bound one ulp or one voxel too loose fails it.
TEST(MaterialBlocks, OnlyNeverPassesAVoxelOfAnotherMaterialAsNear) {
  std::mt19937_64 rng(4940);
  std::uniform_real_distribution<double> fraction(0.0, 1.0);
  long passed = 0, refused = 0, queries = 0, witnesses = 0;
  for (const int pattern : {1, 2, 3, 4}) {
    VoxelGrid grid = painted(edge_grid(32, std::ldexp(1.0, -12)), pattern, 3);
    const fast::MaterialBlocks blocks(grid);
    std::vector<std::size_t> solid;
    for (std::size_t v = 0; v < grid.voxels.size(); ++v) {
      if (grid.voxels[v] != kEmpty) solid.push_back(v);
    }
    const int n = grid.n;
    const double h = grid.voxel_size;
    for (int round = 0; round < 2; ++round) {
      if (round == 1) {  // remove a third of the solid voxels (the pyramid as built)
        for (const std::size_t v : solid) {
          if (fraction(rng) < 0.33) grid.voxels[v] = kEmpty;
        }
      }
      for (int q = 0; q < 400; ++q) {
        const std::size_t v = solid[std::uniform_int_distribution<std::size_t>(
            0, solid.size() - 1)(rng)];
        if (grid.voxels[v] == kEmpty) continue;
        const int ijk[3] = {static_cast<int>(v % n), static_cast<int>((v / n) % n),
                            static_cast<int>(v / (static_cast<std::size_t>(n) * n))};
        // Within 4 voxels of v on each axis: on a grid plane (1 in 2), a quarter-voxel lattice
        // point (1 in 4), else anywhere.
        Vec3 x;
        for (int a = 0; a < 3; ++a) {
          const double u = ijk[a] + 0.5 + 8.0 * (fraction(rng) - 0.5);
          const int how = static_cast<int>(4.0 * fraction(rng));
          x[a] = h * (how < 2 ? std::round(u) : how == 2 ? 0.25 * std::round(4.0 * u) : u);
        }
        const int hi[3] = {ijk[0] + 1, ijk[1] + 1, ijk[2] + 1};
        const double d2 = sdf_detail::box_distance2(grid, ijk, hi, x, nullptr);
        for (std::uint8_t m = kEnamel; m <= kCaries; ++m) {
          ++queries;
          // With a witness: the same answer, and a named voxel solid, of another material, its D
          // (the reference's) < d2 (collide50).
          fast::MaterialBlocks::Witness wit;
          const bool certified = blocks.only(grid, x, d2, m);
          ASSERT_EQ(blocks.only(grid, x, d2, m, &wit), certified);
          if (wit.found) {
            ++witnesses;
            ASSERT_FALSE(certified);
            const std::uint8_t mw = grid.voxels[wit.voxel];
            ASSERT_NE(mw, kEmpty);
            ASSERT_NE(mw, m);
            const int lo[3] = {static_cast<int>(wit.voxel % n),
                               static_cast<int>((wit.voxel / n) % n),
                               static_cast<int>(wit.voxel / (static_cast<std::size_t>(n) * n))};
            const int up[3] = {lo[0] + 1, lo[1] + 1, lo[2] + 1};
            ASSERT_EQ(sdf_detail::box_distance2(grid, lo, up, x, nullptr), wit.d2);
            ASSERT_LT(wit.d2, d2);
          }
          if (!certified) {
            ++refused;
            continue;
          }
          ++passed;
          ASSERT_EQ(m, grid.voxels[v]) << "pattern " << pattern << " x " << x.transpose();
          for (int k = 0; k < n; ++k) {
            for (int j = 0; j < n; ++j) {
              for (int i = 0; i < n; ++i) {
                const std::uint8_t mu = grid.at(i, j, k);
                if (mu == kEmpty || mu == m) continue;
                const int lo[3] = {i, j, k}, up[3] = {i + 1, j + 1, k + 1};
                ASSERT_GT(sdf_detail::box_distance2(grid, lo, up, x, nullptr), d2)
                    << "pattern " << pattern << " voxel " << grid.index(i, j, k);
              }
            }
          }
        }
      }
    }
  }
  std::printf("only(): %ld queries, %ld passed, %ld refused, %ld witnesses\n", queries, passed,
              refused, witnesses);
  EXPECT_GT(passed, queries / 50);  // signal: it certifies (at most 1 material in 4 can)
  EXPECT_GT(witnesses, refused / 10);  // signal: refusals name witnesses
}

// The twin's band depth: the squared centre offsets per axis, (origin + h (i + 1/2)) - g squared,
// summed (x + y) + z and given to cut_band_depth_at, is cut_band_depth's double, at random voxels
// and anchors within a few voxels.
TEST(SurfaceCutSet, BandDepthFromTheAxisTermsIsTheReferencesBitwise) {
  VoxelGrid grid(512, Vec3(-11.3e-3, 2.7e-3, -0.41e-3), 0.0425e-3);
  std::mt19937_64 rng(460);
  std::uniform_int_distribution<int> index(0, grid.n - 1);
  std::uniform_real_distribution<double> off(-6.0, 6.0);
  const double rho = 0.5e-3, band = cut_band(rho).depth;
  long positive = 0;
  for (int q = 0; q < 200000; ++q) {
    const int ijk[3] = {index(rng), index(rng), index(rng)};
    const double r = 0.8 * rho / grid.voxel_size;  // near the band's edge
    Vec3 d(off(rng), off(rng), off(rng));
    d = (r + off(rng)) * d.normalized();
    const Vec3 g = grid.center(ijk[0], ijk[1], ijk[2]) + grid.voxel_size * d;
    double t[3];
    for (int a = 0; a < 3; ++a) {
      const double e = (grid.origin[a] + grid.voxel_size * (ijk[a] + 0.5)) - g[a];
      t[a] = e * e;
    }
    const double fast = cut_band_depth_at((t[0] + t[1]) + t[2], rho, grid.voxel_size, band);
    const double ref = cut_band_depth(grid, ijk[0], ijk[1], ijk[2], g, rho, band);
    ASSERT_EQ(fast, ref) << q;
    positive += ref > 0.0;
  }
  EXPECT_GT(positive, 10000);
}

// ---- The providers along a drilling path ------------------------------------------------------

// A sphere in a block of n^3 voxels of edge h; the bur (radius rho) comes down onto it, drills
// down, sideways, and leaves (the path of tests/fast/field_test.cc, scaled by rho).
struct PathScene {
  int n;
  double h, rho;
  Vec3 centre, top;
  double radius;
  PathScene(int n_, double h_, double rho_) : n(n_), h(h_), rho(rho_) {
    const double side = n * h;
    centre = Vec3(0.503 * side, 0.497 * side, 0.452 * side);
    radius = 0.31 * side;
    top = centre + Vec3(0, 0, radius);
  }
  bool inside(const Vec3& p) const { return (p - centre).norm() < radius; }
  VoxelGrid grid() const {
    return test::solid_grid(n, n * h, [this](const Vec3& p) { return inside(p); });
  }
  static constexpr int kFree = 100, kDown = 500, kSideways = 500, kAway = 100;
  Vec3 bur(int tick) const {
    const Vec3 start = top + Vec3(0, 0, 1.4 * rho);
    if (tick < kFree) return start + Vec3(0.75 * rho, 0, 2.5 * rho) * (1.0 - tick / double(kFree));
    tick -= kFree;
    if (tick < kDown) return start - Vec3(0, 0, 2.75 * rho * tick / kDown);
    tick -= kDown;
    if (tick < kSideways) {
      return start - Vec3(0, 0, 2.75 * rho) + Vec3(1.5 * rho * tick / kSideways, 0.25 * rho, 0);
    }
    tick -= kSideways;
    return start + Vec3(1.5 * rho, 0, 7.5 * rho * std::min(1.0, tick / 100.0));
  }
};

// The reference provider and the fast one (sdf, or field at `stride`) along the path.
void providers_agree(const PathScene& p, ContactModel model, int stride) {
  SCOPED_TRACE(std::string(contact_model_name(model)) + " n " + std::to_string(p.n) + " stride " +
               std::to_string(stride));
  const VoxelGrid g = p.grid();
  VoxelTooth tooth_r(g), tooth_f(g);
  SampledField field_r, field_f;
  if (model == ContactModel::kField) {
    field_r = build_sampled_field(
        g, triangulate_implicit(g, [&p](const Vec3& x) { return p.inside(x); }),
        field_band_for_tip(p.rho, g.voxel_size, stride));
    field_f = field_r;
  }
  DrillParams drill;
  drill.cutting_coefficient = 10.0;  // cuts fast: hundreds of voxels on this path
  const ToolTip tip{p.rho, Vec3::Zero()};
  ToothContactProvider reference(tooth_r, tip, kK, kB, &drill, model, &signed_distance,
                                 model == ContactModel::kField ? &field_r : nullptr);
  PipelineToothSetup setup;
  setup.tip = tip;
  setup.k_tooth = kK;
  setup.b_tooth = kB;
  setup.drilling = &drill;
  setup.contact_model = model;
  setup.field = model == ContactModel::kField ? &field_f : nullptr;
  setup.field_edit_latency = 0;  // the budget path on this thread (the worker: field_test.cc)
  std::unique_ptr<fast::CutSetProvider> fast_provider;
  if (model == ContactModel::kField) {
    fast_provider = std::make_unique<fast::FieldContactProvider>(tooth_f, setup);
  } else {
    fast_provider = std::make_unique<fast::SdfContactProvider>(tooth_f, setup);
  }
  std::vector<Contact> out_r, out_f;
  out_r.reserve(kContactCapacity);
  out_f.reserve(kContactCapacity);
  const int ticks = PathScene::kFree + PathScene::kDown + PathScene::kSideways + PathScene::kAway;
  long contact_ticks = 0, removed = 0, members = 0, allocations = 0;
  std::size_t most = 0;
  {
    testing::AllocationScope scope;
    for (int tick = 0; tick < ticks; ++tick) {
      Pose pose;
      pose.x = p.bur(tick);
      ASSERT_EQ(reference.contacts(pose, out_r), fast_provider->contacts(pose, out_f));
      ASSERT_EQ(out_r.size(), out_f.size()) << "tick " << tick;
      for (std::size_t i = 0; i < out_r.size(); ++i) {
        ASSERT_TRUE(same(out_r[i], out_f[i])) << "tick " << tick;
      }
      ASSERT_EQ(first_difference(reference.cut_shares(), reference.cut_voxels(),
                                 fast_provider->cut_shares(), fast_provider->cut_voxels()),
                -1)
          << "tick " << tick << ": " << reference.cut_shares().size() << " members, fast "
          << fast_provider->cut_shares().size();
      members += static_cast<long>(reference.cut_shares().size());
      most = std::max(most, reference.cut_shares().size());
      const int rr = reference.drill(out_r, kT);
      ASSERT_EQ(rr, fast_provider->drill(out_f, kT)) << "tick " << tick;
      ASSERT_EQ(reference.last_removed(), fast_provider->last_removed()) << "tick " << tick;
      contact_ticks += out_r.empty() ? 0 : 1;
      removed += rr;
    }
    allocations = scope.count();
  }
  const fast::SurfaceCutSet& cut = fast_provider->cut_set();
  std::printf("%s n %d h %.4f mm stride %d: %d ticks, %ld in contact, %ld cut members (at most "
              "%zu), %ld voxels removed; material by sd %ld of %ld; %ld allocations\n",
              contact_model_name(model), p.n, 1e3 * p.h, stride, ticks, contact_ticks, members,
              most, removed, cut.fallbacks(), cut.queries(), allocations);
  EXPECT_EQ(tooth_r.grid().voxels, tooth_f.grid().voxels);
  EXPECT_EQ(bits_differing(cut.surface(), tooth_f), 0);
  EXPECT_EQ(reference.drill_state().delivered_j, fast_provider->drill_state().delivered_j);
  EXPECT_EQ(reference.drill_state().carry_j, fast_provider->drill_state().carry_j);
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(contact_ticks, 600);
  EXPECT_GT(removed, 100);  // signal: the cut set was cut
  EXPECT_EQ(cut.queries(), contact_ticks);
  EXPECT_LT(cut.fallbacks(), contact_ticks / 10);
}

// h = 0.25, 0.125, 0.0625 mm and the 512^3 molar's 0.0425 mm (rho / h = 11.8: ~900 members).
TEST(CutSetProvider, SdfEqualsTheReferenceWhileDrillingAtFourResolutions) {
  providers_agree(PathScene(32, 0.25e-3, 0.5e-3), ContactModel::kSurfaceProxy, 1);
  providers_agree(PathScene(64, 0.125e-3, 0.5e-3), ContactModel::kSurfaceProxy, 1);
  providers_agree(PathScene(128, 0.0625e-3, 0.5e-3), ContactModel::kSurfaceProxy, 1);
  providers_agree(PathScene(128, 0.0425e-3, 0.5e-3), ContactModel::kSurfaceProxy, 1);
}

TEST(CutSetProvider, FieldEqualsTheReferenceWhileDrillingAtStrides1And2) {
  providers_agree(PathScene(64, 0.125e-3, 0.5e-3), ContactModel::kField, 1);
  providers_agree(PathScene(64, 0.125e-3, 0.5e-3), ContactModel::kField, 2);
  providers_agree(PathScene(128, 0.0425e-3, 0.5e-3), ContactModel::kField, 2);
}

// ---- The drill scene's closed loop --------------------------------------------------------------

// The drill scene in the fast pipeline, twice: with its tooth's provider (the fast voxel side) and
// with the reference's provider on the second rig's tooth and field (the reference voxel side; the
// field edit at the fast pipeline's latency, as the fast provider's worker). Each loop is built
// alike (no safety chain on either).
void drill_scene_agrees(const std::string& contact_model, int ticks) {
  SCOPED_TRACE(contact_model);
  Scene scene = load_scene("drill");
  scene.tooth.contact_model = contact_model;
  SceneRigOptions options;
  options.pipeline = "fast";
  const std::unique_ptr<SceneRig> a = build_scene_rig(scene, options);
  const std::unique_ptr<SceneRig> b = build_scene_rig(scene, options);
  const auto* fast_provider = dynamic_cast<fast::CutSetProvider*>(a->contacts);
  ASSERT_NE(fast_provider, nullptr);
  const ContactModel model = parse_contact_model(contact_model);
  ASSERT_EQ(fast_provider->model(), model);
  DrillParams drill;
  drill.bur_speed_rad_s = scene.tool.bur_speed_rpm * 2.0 * 3.14159265358979323846 / 60.0;
  drill.cutting_coefficient = scene.tool.cutting_coefficient;
  ToothContactProvider reference(*b->tooth, b->tip, b->k_tooth, b->b_tooth, &drill, model,
                                 &fast::signed_distance, b->field.get());
  if (model == ContactModel::kField) {
    reference.set_field_edit_latency(ToothContactProvider::kFieldEditLatency);
  }
  ClosedLoop loop_a(*a->loop_device, *a->pipeline, *a->contacts);
  ClosedLoop loop_b(*b->loop_device, *b->pipeline, reference);
  loop_a.start();
  loop_b.start();
  long contact_ticks = 0, removed = 0;
  for (int k = 0; k < ticks; ++k) {
    const TickResult& ra = loop_a.step();
    const TickResult& rb = loop_b.step();
    ASSERT_EQ(ra.F_contact, rb.F_contact) << "tick " << k;
    ASSERT_EQ(ra.tau, rb.tau) << "tick " << k;
    ASSERT_EQ(ra.removed_voxels, rb.removed_voxels) << "tick " << k;
    contact_ticks += ra.contacts.empty() ? 0 : 1;
    removed += ra.removed_voxels;
  }
  const DrillState& sa = a->contacts->drill_state();
  const DrillState& sb = reference.drill_state();
  double va = 0.0, vb = 0.0;
  for (int m = kEnamel; m < kMaterialCount; ++m) {
    va += sa.removed_volume_m3(m);
    vb += sb.removed_volume_m3(m);
  }
  std::printf("drill scene, %s: %d ticks, %ld in contact, %ld voxels removed, %.6f mm^3; "
              "material by sd %ld of %ld\n",
              contact_model.c_str(), ticks, contact_ticks, removed, 1e9 * va,
              fast_provider->cut_set().fallbacks(), fast_provider->cut_set().queries());
  EXPECT_EQ(va, vb);
  EXPECT_EQ(sa.delivered_j, sb.delivered_j);
  EXPECT_EQ(a->tooth->grid().voxels, b->tooth->grid().voxels);
  EXPECT_GT(contact_ticks, ticks / 3);
  EXPECT_GT(removed, 50);
}

TEST(CutSetProvider, TheDrillSceneRemovesAndPushesTheSameWithEitherVoxelSide) {
  drill_scene_agrees("sdf", 3000);
  drill_scene_agrees("field", 3000);
}

}  // namespace
}  // namespace dentsim
