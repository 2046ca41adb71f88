#include "reference/tooth/drilling.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "reference/core/contact_provider.h"
#include "reference/core/io.h"

namespace dentsim {

std::size_t count_surface_voxels(const VoxelGrid& grid) {
  std::size_t count = 0;
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (grid.at(i, j, k) == kEmpty) continue;
        bool exposed = false;
        for (int f = 0; f < 6 && !exposed; ++f) {
          int nb[3] = {i, j, k};
          nb[face_axis(f)] += face_sign(f);
          exposed = grid.at(nb[0], nb[1], nb[2]) == kEmpty;  // outside the grid reads empty
        }
        if (exposed) ++count;
      }
    }
  }
  return count;
}

std::size_t drill_work_capacity(std::size_t surface_voxels) {
  return 2 * surface_voxels + kContactCapacity;
}

DrillState make_drill_state(const VoxelGrid& grid, std::size_t capacity) {
  DrillState state;
  state.work_j.reserve(capacity > 0 ? capacity : drill_work_capacity(count_surface_voxels(grid)));
  state.voxel_volume_m3 = grid.voxel_volume();
  state.grid_voxels = grid.voxels.size();
  return state;
}

bool accumulate_drill_work(std::span<const Contact> contacts,
                           std::span<const std::size_t> contact_voxels, const ToolTip& tip,
                           const DrillParams& params, double T, DrillState* state) {
  double total_weight = 0.0;
  for (const Contact& ct : contacts) total_weight += ct.weight;
  if (!(total_weight > 0.0)) return false;
  if (!state->work_j.has_room(contacts.size())) {  // every voxel of the set might be new
    state->work_table_full = true;
    return false;
  }
  // W_i = mu_c f_i omega rho T_k with f_i the contact's share of the blended normal force.
  const double speed = params.bur_speed_rad_s * tip.radius;  // u = omega rho [m/s]
  const auto work_of = [&](const Contact& ct) {
    const double f_i = ct.weight / total_weight * ct.stiffness * std::max(0.0, ct.depth);
    return params.cutting_coefficient * f_i * speed * T;
  };
  double delivered = 0.0;
  for (const Contact& ct : contacts) delivered += work_of(ct);
  state->delivered_j += delivered;
  // The carry of the last removals: a surplus (> 0) is shared as the force is (weight / total
  // weight); a debt (< 0) is paid first: the tick's work is scaled by (delivered - paid) /
  // delivered, the rest of the debt waits for the next ticks.
  const double surplus = std::max(0.0, state->carry_j);
  double scale = 1.0;
  double carry_after = 0.0;
  if (state->carry_j < 0.0) {
    const double paid = std::min(-state->carry_j, delivered);
    if (paid > 0.0) scale = (delivered - paid) / delivered;
    carry_after = state->carry_j + paid;
  }
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const Contact& ct = contacts[i];
    double w = work_of(ct) * scale;
    if (surplus > 0.0) w += surplus * (ct.weight / total_weight);
    state->work_j.add(contact_voxels[i], w);
  }
  state->carry_j = carry_after;
  return true;
}

void collect_cut_set(const VoxelTooth& tooth, const Contact& contact, const Vec3& g, double rho,
                     std::vector<std::size_t>* candidates, std::vector<Contact>* shares,
                     std::vector<std::size_t>* voxels) {
  const VoxelGrid& grid = tooth.grid();
  candidates->clear();
  const CutBand cut = cut_band(rho);  // the bur's cutting band about g
  const double band = cut.depth;
  tooth.octree.query_sphere(g, cut.reach, candidates);  // the solid voxels the band meets
  const std::size_t n = static_cast<std::size_t>(grid.n);
  for (const std::size_t v : *candidates) {
    if (tooth.codes.code(v) == 0) continue;  // no exposed face: under the cut surface
    if (shares->size() >= shares->capacity() || voxels->size() >= voxels->capacity()) break;
    const double depth =
        cut_band_depth(grid, static_cast<int>(v % n), static_cast<int>((v / n) % n),
                       static_cast<int>(v / (n * n)), g, rho, band);
    if (!(depth > 0.0)) continue;
    Contact share = contact;  // the contact's force K delta, shared by the band's depth
    share.material = grid.voxels[v];
    share.weight = depth;
    shares->push_back(share);
    voxels->push_back(v);
  }
}

void validate_drill_params(const DrillParams& params) {
  if (!(params.bur_speed_rad_s >= 0.0) || !(params.cutting_coefficient >= 0.0) ||
      !std::isfinite(params.bur_speed_rad_s) || !std::isfinite(params.cutting_coefficient)) {
    throw InputError("drill params: bur_speed_rad_s and cutting_coefficient must be finite and "
                     ">= 0");
  }
}

double removal_threshold_j(std::uint8_t material, double voxel_size) {
  if (material == kEmpty || material >= kMaterialCount) {
    throw InputError("removal_threshold_j: material id " + std::to_string(material) +
                     ", expected 1 (enamel), 2 (dentin), 3 (pulp) or 4 (caries)");
  }
  constexpr double kJoulePerMm3ToJoulePerM3 = 1e9;
  return material_properties(material).removal_energy_j_per_mm3 * kJoulePerMm3ToJoulePerM3 *
         voxel_size * voxel_size * voxel_size;
}

bool removal_opens_pulp(const VoxelGrid& grid, int i, int j, int k) {
  bool opens = grid.at(i, j, k) == kPulp;
  for (int f = 0; f < 6 && !opens; ++f) {
    int nb[3] = {i, j, k};
    nb[face_axis(f)] += face_sign(f);
    opens = grid.at(nb[0], nb[1], nb[2]) == kPulp;
  }
  return opens;
}

void account_removed_voxel(std::size_t v, std::uint8_t material, double work, double threshold,
                           DrillState* state, std::vector<std::size_t>* removed) {
  state->work_j.erase(v);
  state->carry_j += work - threshold;  // a surplus (W > E_m) or a debt (W < E_m) carried on
  ++state->removed_voxels[material];
  if (removed != nullptr) removed->push_back(v);
}

int drill_tick(std::span<const Contact> contacts, std::span<const std::size_t> contact_voxels,
               const ToolTip& tip, const DrillParams& params, double T, VoxelTooth* tooth,
               DrillState* state, std::vector<std::size_t>* removed) {
  if (contacts.size() != contact_voxels.size()) {
    throw InputError("drill_tick: " + std::to_string(contacts.size()) + " contacts but " +
                     std::to_string(contact_voxels.size()) + " contact voxels, expected equal");
  }
  if (!(T > 0.0) || !std::isfinite(T)) {
    throw InputError("drill_tick: T = " + std::to_string(T) + ", expected a finite tick > 0 [s]");
  }
  if (!(params.bur_speed_rad_s >= 0.0) || !(params.cutting_coefficient >= 0.0)) {
    throw InputError("drill params: bur_speed_rad_s and cutting_coefficient must be >= 0");
  }
  if (state->grid_voxels != tooth->grid().voxels.size()) {
    throw InputError("drill_tick: drill state sized for another tooth");
  }
  if (!accumulate_drill_work(contacts, contact_voxels, tip, params, T, state)) return 0;

  int count = 0;
  const VoxelGrid& grid = tooth->grid();
  const int n = grid.n;
  const double h = grid.voxel_size;
  for (const std::size_t v : contact_voxels) {
    const std::uint8_t material = grid.voxels[v];
    if (material == kEmpty) continue;  // already removed this tick (several faces of one voxel)
    const double work = state->work_j.get(v);
    const double threshold = removal_threshold_j(material, h);
    if (!removal_due(work, threshold)) continue;
    const int i = static_cast<int>(v % n);
    const int j = static_cast<int>((v / n) % n);
    const int k = static_cast<int>(v / (static_cast<std::size_t>(n) * n));
    if (!state->pulp_exposed) state->pulp_exposed = removal_opens_pulp(grid, i, j, k);
    tooth->octree.remove_voxel(i, j, k);
    reencode_local(tooth->octree.grid(), i, j, k, &tooth->codes);
    account_removed_voxel(v, material, work, threshold, state, removed);
    ++count;
  }
  return count;
}

}  // namespace dentsim
