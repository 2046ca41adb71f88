#include "fast/tooth/drilling.h"

#include <array>
#include <cmath>

namespace dentsim::fast {

int drill_tick(std::span<const Contact> contacts, std::span<const std::size_t> contact_voxels,
               const ToolTip& tip, const DrillParams& params, double T, BrickTooth* tooth,
               DrillState* state, std::vector<std::size_t>* removed) {
  if (contacts.size() != contact_voxels.size() || !(T > 0.0) || !std::isfinite(T) ||
      !(params.bur_speed_rad_s >= 0.0) || !(params.cutting_coefficient >= 0.0) ||
      state->grid_voxels != tooth->grid().voxels.size()) {
    return 0;
  }
  if (!accumulate_drill_work(contacts, contact_voxels, tip, params, T, state)) return 0;

  // Thresholds of the three materials, by the reference's expression (removal_threshold_j).
  const double h = tooth->grid().voxel_size;
  std::array<double, kMaterialCount> threshold{};
  for (std::uint8_t m = kEnamel; m < kMaterialCount; ++m) threshold[m] = removal_threshold_j(m, h);

  int count = 0;
  const int n = tooth->grid().n;
  for (const std::size_t v : contact_voxels) {
    const std::uint8_t material = tooth->grid().voxels[v];
    if (material == kEmpty) continue;  // already removed this tick (several faces of one voxel)
    const double work = state->work_j.get(v);
    if (!removal_due(work, threshold[material])) continue;
    const int i = static_cast<int>(v % n);
    const int j = static_cast<int>((v / n) % n);
    const int k = static_cast<int>(v / (static_cast<std::size_t>(n) * n));
    if (!state->pulp_exposed) state->pulp_exposed = removal_opens_pulp(tooth->grid(), i, j, k);
    tooth->remove_voxel(i, j, k);
    account_removed_voxel(v, material, work, threshold[material], state, removed);
    ++count;
  }
  return count;
}

}  // namespace dentsim::fast
