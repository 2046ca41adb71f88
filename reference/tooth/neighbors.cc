#include "reference/tooth/neighbors.h"

namespace dentsim {
namespace {

constexpr int kStep[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};

}  // namespace

std::uint8_t exposed_faces(const VoxelGrid& grid, int i, int j, int k) {
  if (!grid.solid(i, j, k)) return 0;
  std::uint8_t code = 0;
  for (int f = 0; f < 6; ++f) {
    // VoxelGrid::solid is false outside the grid, so boundary faces are exposed.
    if (!grid.solid(i + kStep[f][0], j + kStep[f][1], k + kStep[f][2])) {
      code |= static_cast<std::uint8_t>(1u << f);
    }
  }
  return code;
}

NeighborCodes encode_neighbors(const VoxelGrid& grid) {
  NeighborCodes codes;
  codes.n = grid.n;
  codes.code.assign(grid.voxels.size(), 0);
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i)
        codes.code[grid.index(i, j, k)] = exposed_faces(grid, i, j, k);
    }
  }
  return codes;
}

void reencode_local(const VoxelGrid& grid, int i, int j, int k, NeighborCodes* codes) {
  if (grid.inside(i, j, k)) codes->code[grid.index(i, j, k)] = exposed_faces(grid, i, j, k);
  for (int f = 0; f < 6; ++f) {
    const int a = i + kStep[f][0], b = j + kStep[f][1], c = k + kStep[f][2];
    if (grid.inside(a, b, c)) codes->code[grid.index(a, b, c)] = exposed_faces(grid, a, b, c);
  }
}

}  // namespace dentsim
