// The octree memory table of `dentsim crosscheck octree --json` (validation/crosscheck_octree.h,
// docs/tooth_octree.md) against its closed form: a full octree over N^3 voxels (N = 2^L) has
// (8^L - 1) / 7 internal nodes of one mask byte each, and one material byte per voxel; the
// neighbour codes take one byte and the drilling work one double per voxel.
#include "validation/crosscheck_octree.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace dentsim {
namespace {

TEST(CrosscheckOctreeJson, MemoryTableIsTheClosedForm) {
  const nlohmann::json rows = octree_memory_table_json();
  ASSERT_EQ(rows.size(), 5u);  // 32, 64, 128, 256, 512
  std::uint64_t n = 32;
  int levels = 5;
  for (const auto& row : rows) {
    const std::uint64_t masks = ((std::uint64_t{1} << (3 * levels)) - 1) / 7;
    EXPECT_EQ(row["n"].get<std::uint64_t>(), n);
    EXPECT_EQ(row["levels"].get<int>(), levels);
    EXPECT_EQ(row["internal_nodes"].get<std::uint64_t>(), masks);
    EXPECT_EQ(row["mask_bytes"].get<std::uint64_t>(), masks);
    EXPECT_EQ(row["leaf_bytes"].get<std::uint64_t>(), n * n * n);
    EXPECT_EQ(row["octree_bytes"].get<std::uint64_t>(), masks + n * n * n);
    EXPECT_EQ(row["neighbor_code_bytes"].get<std::uint64_t>(), n * n * n);
    EXPECT_EQ(row["drill_work_bytes"].get<std::uint64_t>(), 8 * n * n * n);
    n *= 2;
    ++levels;
  }
}

TEST(CrosscheckOctreeJson, CarriesTheOptionsAndCounts) {
  OctreeCrosscheckOptions o;
  o.n = 8;
  o.spheres = 300;
  o.seed = 7;
  o.remove_every = 10;
  const OctreeCrosscheckResult r = crosscheck_octree(o);
  const nlohmann::json j = crosscheck_octree_json(o, r);
  EXPECT_EQ(r.queries, 300);
  EXPECT_EQ(r.mismatches, 0);
  EXPECT_EQ(j["n"].get<int>(), 8);
  EXPECT_EQ(j["seed"].get<std::uint64_t>(), 7u);
  EXPECT_EQ(j["remove_every"].get<long>(), 10);
  EXPECT_EQ(j["queries"].get<long>(), r.queries);
  EXPECT_EQ(j["removals"].get<long>(), r.removals);
  long placed = 0;
  for (const auto& [name, count] : j["by_placement"].items()) placed += count.get<long>();
  EXPECT_EQ(placed, r.queries);  // every query has one placement
  EXPECT_EQ(j["first_mismatch"].get<std::string>(), "");
}

}  // namespace
}  // namespace dentsim
