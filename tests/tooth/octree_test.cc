// Full octree (reference/tooth/octree.h): node indexing, memory, per-level occupancy against the
// leaves, exact sphere queries against brute force (exact: integer sets), removal updates.
#include "reference/tooth/octree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <set>

#include "reference/core/io.h"

namespace dentsim {
namespace {

constexpr std::uint64_t kSeed = 20261121;

// Random occupancy with materials 1..3, probability `fill` of being solid.
VoxelGrid random_grid(int n, double fill, std::uint64_t seed) {
  VoxelGrid g(n, Vec3(0.25e-3, -0.5e-3, 1e-3), 0.1e-3);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto& v : g.voxels) v = u(rng) < fill ? static_cast<std::uint8_t>(1 + rng() % 3) : 0;
  return g;
}

// Oracle: every voxel of the flat array.
std::vector<std::size_t> brute(const VoxelGrid& g, const Vec3& c, double rho) {
  std::vector<std::size_t> out;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        if (g.solid(i, j, k) && sphere_intersects_voxel(g, i, j, k, c, rho)) {
          out.push_back(g.index(i, j, k));
        }
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::size_t> query(const FullOctree& t, const Vec3& c, double rho) {
  std::vector<std::size_t> out;
  t.query_sphere(c, rho, &out);
  std::sort(out.begin(), out.end());
  return out;
}

TEST(FullOctree, NodeIndexIsTheFullOctreeLinearIndex) {
  EXPECT_EQ(FullOctree::node_index(0, 0, 0, 0), 0u);
  EXPECT_EQ(FullOctree::node_index(1, 0, 0, 0), 1u);
  EXPECT_EQ(FullOctree::node_index(1, 1, 1, 1), 8u);
  EXPECT_EQ(FullOctree::node_index(2, 0, 0, 0), 9u);
  // Children of g are 8 g + 1 + c, c = cx + 2 cy + 4 cz; parent of g is (g - 1) / 8.
  for (int l = 0; l < 5; ++l) {
    const int nl = 1 << l;
    for (int z = 0; z < nl; ++z) {
      for (int y = 0; y < nl; ++y) {
        for (int x = 0; x < nl; ++x) {
          const std::size_t g = FullOctree::node_index(l, x, y, z);
          for (int c = 0; c < 8; ++c) {
            const std::size_t child = FullOctree::node_index(
                l + 1, 2 * x + (c & 1), 2 * y + ((c >> 1) & 1), 2 * z + ((c >> 2) & 1));
            ASSERT_EQ(child, 8 * g + 1 + c);
            ASSERT_EQ((child - 1) / 8, g);
          }
        }
      }
    }
  }
  // A bijection of each level onto [(8^l - 1) / 7, (8^(l+1) - 1) / 7).
  for (int l = 0; l <= 4; ++l) {
    const int nl = 1 << l;
    std::set<std::size_t> seen;
    for (int z = 0; z < nl; ++z) {
      for (int y = 0; y < nl; ++y) {
        for (int x = 0; x < nl; ++x) seen.insert(FullOctree::node_index(l, x, y, z));
      }
    }
    EXPECT_EQ(seen.size(), static_cast<std::size_t>(nl) * nl * nl);
    EXPECT_EQ(*seen.begin(), FullOctree::internal_node_count(l));
    EXPECT_EQ(*seen.rbegin() + 1, FullOctree::internal_node_count(l + 1));
  }
}

TEST(FullOctree, MemoryPerResolution) {
  // (8^L - 1) / 7 mask bytes + N^3 leaf bytes: the table of docs/tooth_octree.md.
  EXPECT_EQ(FullOctree::memory_bytes_for(32), 4681u + 32768u);
  EXPECT_EQ(FullOctree::memory_bytes_for(64), 37449u + 262144u);
  EXPECT_EQ(FullOctree::memory_bytes_for(128), 299593u + 2097152u);
  EXPECT_EQ(FullOctree::memory_bytes_for(256), 2396745u + 16777216u);
  EXPECT_EQ(FullOctree::memory_bytes_for(512), 19173961u + 134217728u);
  for (int n = 1; n <= 64; n *= 2) {
    const FullOctree t(random_grid(n, 0.5, kSeed));
    EXPECT_EQ(t.memory_bytes(), FullOctree::memory_bytes_for(n)) << "n=" << n;
  }
}

TEST(FullOctree, EveryLevelOccupancyEqualsItsLeaves) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  for (const double fill : {0.002, 0.05, 0.5, 1.0}) {
    const VoxelGrid g = random_grid(16, fill, kSeed);
    const FullOctree t(g);
    ASSERT_EQ(t.levels(), 4);
    for (int l = 0; l <= 4; ++l) {
      const int nl = 1 << l, s = 16 >> l;
      for (int z = 0; z < nl; ++z) {
        for (int y = 0; y < nl; ++y) {
          for (int x = 0; x < nl; ++x) {
            bool any = false;
            for (int k = z * s; k < (z + 1) * s; ++k) {
              for (int j = y * s; j < (y + 1) * s; ++j) {
                for (int i = x * s; i < (x + 1) * s; ++i) any = any || g.solid(i, j, k);
              }
            }
            ASSERT_EQ(t.occupied(l, x, y, z), any) << "fill " << fill << " level " << l;
          }
        }
      }
    }
  }
}

// Every internal node's byte, bit by bit, against its definition (child c = cx + 2 cy + 4 cz holds
// a solid voxel of its span), over grids solid up to their boundary, from one voxel to 32^3: the
// constructor reads the leaves' rows and the levels in Morton order (issue #30), not occupied().
TEST(FullOctree, EveryChildMaskBitIsItsChildsOccupancy) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  for (const int n : {1, 2, 4, 32}) {
    for (const double fill : {0.0, 0.01, 0.3, 1.0}) {
      const VoxelGrid g = random_grid(n, fill, kSeed + static_cast<std::uint64_t>(n));
      const FullOctree t(g);
      ASSERT_EQ(t.masks().size(), FullOctree::internal_node_count(t.levels()));
      for (int l = 0; l < t.levels(); ++l) {
        const int nl = 1 << l, s = n >> (l + 1);  // s: a child's edge in voxels
        for (int z = 0; z < nl; ++z) {
          for (int y = 0; y < nl; ++y) {
            for (int x = 0; x < nl; ++x) {
              int expected = 0;
              for (int c = 0; c < 8; ++c) {
                const int i0 = (2 * x + (c & 1)) * s, j0 = (2 * y + ((c >> 1) & 1)) * s,
                          k0 = (2 * z + ((c >> 2) & 1)) * s;
                bool any = false;
                for (int k = k0; k < k0 + s; ++k) {
                  for (int j = j0; j < j0 + s; ++j) {
                    for (int i = i0; i < i0 + s; ++i) any = any || g.solid(i, j, k);
                  }
                }
                if (any) expected |= 1 << c;
              }
              ASSERT_EQ(t.child_mask(l, x, y, z), expected)
                  << "n " << n << " fill " << fill << " level " << l << " node " << x << ","
                  << y << "," << z;
            }
          }
        }
      }
    }
  }
}

TEST(FullOctree, SphereQueriesExactOnAUnitGrid) {
  // All-solid 8^3 grid, h = 1, origin 0: distances to voxel boxes are exact integers' roots.
  VoxelGrid g(8, Vec3::Zero(), 1.0);
  std::fill(g.voxels.begin(), g.voxels.end(), kDentin);
  const FullOctree t(g);
  const Vec3 p(4, 4, 4);  // the corner shared by 8 voxels, also the level-1 node corner
  EXPECT_EQ(query(t, p, 0.5).size(), 8u);
  EXPECT_EQ(query(t, p, 1.0).size(), 8u);  // boxes at distance exactly 1 are only touched
  EXPECT_EQ(query(t, p, std::nextafter(1.0, 2.0)).size(), 8u + 24u);
  EXPECT_EQ(query(t, p, std::sqrt(2.0) * 0.999).size(), 32u);
  // Touching the grid's outer face from outside: nothing; one ulp closer: the 4 voxels at (0,*,*).
  EXPECT_TRUE(query(t, Vec3(-1.0, 4, 4), 1.0).empty());
  EXPECT_EQ(query(t, Vec3(-1.0, 4, 4), std::nextafter(1.0, 2.0)).size(), 2u * 2u);
  // The whole grid.
  EXPECT_EQ(query(t, p, 100.0).size(), 512u);
}

TEST(FullOctree, SphereQueriesEqualBruteForce) {
  std::mt19937_64 rng(kSeed);
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  long nonempty = 0, total = 0;
  for (const double fill : {0.01, 0.3, 0.9}) {
    const FullOctree t(random_grid(16, fill, kSeed + 1));
    const VoxelGrid& g = t.grid();
    for (int q = 0; q < 3000; ++q) {
      Vec3 c_vox(u(rng) * 20 - 2, u(rng) * 20 - 2, u(rng) * 20 - 2);
      if (q % 3 == 0) c_vox = c_vox.array().round();  // on voxel and octree-cell corners
      const double rho = g.voxel_size * (q % 5 == 0 ? std::round(1 + 3 * u(rng)) : 4 * u(rng));
      const Vec3 c = g.origin + g.voxel_size * c_vox;
      const auto expected = brute(g, c, rho);
      ASSERT_EQ(query(t, c, rho), expected) << "query " << q << " fill " << fill;
      nonempty += !expected.empty();
      ++total;
    }
  }
  EXPECT_GT(nonempty, total / 2);  // the queries exercise the descent
}

TEST(FullOctree, RemovalUpdatesEveryLevelUpToTheRoot) {
  FullOctree t(random_grid(16, 0.4, kSeed));
  std::mt19937_64 rng(kSeed);
  std::vector<std::size_t> order(t.grid().voxels.size());
  for (std::size_t v = 0; v < order.size(); ++v) order[v] = v;
  std::shuffle(order.begin(), order.end(), rng);
  long removed = 0;
  for (std::size_t step = 0; step < order.size(); ++step) {
    const std::size_t v = order[step];
    const int i = static_cast<int>(v % 16), j = static_cast<int>((v / 16) % 16),
              k = static_cast<int>(v / 256);
    const std::uint8_t before = t.grid().at(i, j, k);
    ASSERT_EQ(t.remove_voxel(i, j, k), before);
    ASSERT_EQ(t.grid().at(i, j, k), kEmpty);
    removed += before != kEmpty;
    if (step % 97 == 0 || step + 1 == order.size()) {
      const FullOctree rebuilt(t.grid());
      ASSERT_EQ(t.masks(), rebuilt.masks()) << "after " << step + 1 << " removals";
    }
  }
  EXPECT_GT(removed, 1000);
  EXPECT_FALSE(t.occupied(0, 0, 0, 0));
  EXPECT_TRUE(query(t, t.grid().origin, 1.0).empty());
  EXPECT_EQ(t.remove_voxel(0, 0, 0), kEmpty);  // removing an empty voxel changes nothing
  EXPECT_THROW(t.remove_voxel(16, 0, 0), InputError);
}

TEST(FullOctree, RejectsBadGrids) {
  EXPECT_THROW(FullOctree(VoxelGrid(3, Vec3::Zero(), 1e-4)), InputError);
  EXPECT_THROW(FullOctree(VoxelGrid(4, Vec3::Zero(), 0.0)), InputError);
  VoxelGrid bad(4, Vec3::Zero(), 1e-4);
  bad.voxels[5] = 7;
  EXPECT_THROW(FullOctree{bad}, InputError);
  VoxelGrid short_grid(4, Vec3::Zero(), 1e-4);
  short_grid.voxels.pop_back();
  EXPECT_THROW(FullOctree{short_grid}, InputError);
  try {
    const FullOctree t{VoxelGrid(6, Vec3::Zero(), 1e-4)};
    ADD_FAILURE() << "n = 6 accepted, levels " << t.levels();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("power of two"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dentsim
