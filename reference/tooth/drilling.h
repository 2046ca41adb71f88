// Drilling of the voxel tooth (thesis §2.5.2 "Drilling"; docs/design.md "Voxel tooth", last stage
// of "One servo tick").
//
// Model (docs/tooth_octree.md "Drilling"): the bur is the tip sphere of radius rho spinning at
// omega [rad/s]; its cutting surface moves at u = omega rho [m/s] against the tooth. Contact i of
// the tick's set (reference/tooth/collision.h) carries the normal force share
//   f_i = (w_i / sum_j w_j) K_i depth_i                   [N]  (the blend of the contact stage)
// and the bur's tangential cutting force mu_c f_i (mu_c: cutting coefficient, the ratio of
// tangential to normal bur force) does the work
//   W_i = mu_c f_i u T_k = mu_c f_i omega rho T_k          [J]
// on contact i's voxel during the tick of length T_k [s]. Each voxel sums the work done on it over
// the ticks; its material's threshold is
//   E_m = removal_energy_j_per_mm3(m) * 1e9 [J/m^3] * h^3   (materials.cc: enamel 3.0 J/mm^3,
//                                                           dentin 0.6 J/mm^3, pulp 0.01 J/mm^3)
// and it is removed once its work reaches theta E_m, theta = kRemovalFraction = 1/2: the cut front
// has passed its centre (issue #30). FullOctree::remove_voxel updates the occupancy up to the root
// and reencode_local re-encodes it and its six neighbours. Removed voxels never come back. The
// removed volume is counted per material, each voxel at its whole E_m: a voxel removed with
// W != E_m leaves the difference in a signed carry (DrillState::carry_j): a surplus W - E_m > 0 is
// shared by the next tick's set, a debt E_m - W > 0 is paid first from the next ticks' work. So
// delivered = sum_m e_m V_m + stored work + carry exactly; a wall voxel keeps < E_m / 2, so the O(h)
// deficit of the removed volume is about a quarter of the old law's (drilling.md §1-2).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "reference/core/params.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/materials.h"
#include "reference/tooth/voxel_work.h"

namespace dentsim {

struct DrillParams {
  // omega [rad/s]. Default 300 000 rpm: an air-turbine handpiece such as the thesis's KaVo
  // Super-Torque 625C (§4.1) runs at a few 10^5 rpm.
  double bur_speed_rad_s = 300000.0 * 2.0 * 3.14159265358979323846 / 60.0;
  // mu_c, tangential / normal bur force: a model parameter (documented in docs/tooth_octree.md).
  double cutting_coefficient = 0.5;
};

struct DrillState {
  // Accumulated work per voxel [J], stored only where non-zero (sized at setup, never grown).
  VoxelWorkTable work_j;
  std::array<std::int64_t, kMaterialCount> removed_voxels{};  // count per material id
  double voxel_volume_m3 = 0.0;                               // h^3
  // Set by the first removal that opens the pulp: a pulp voxel removed, or a removed voxel
  // face-adjacent to a pulp voxel (the chamber is then open to the cavity). The loop owner
  // stamps the time (report.json pulp_exposed_at_s).
  bool pulp_exposed = false;
  // Set (and kept) when a tick's contact voxels did not fit the work table: that tick added no
  // work and removed nothing; the loop owner ends the run in the named fault
  // tick_drill_work_table_full (TickStatus::kDrillWorkTableFull).
  bool work_table_full = false;
  // The grid the state was made for (flat voxel count), checked by drill_tick.
  std::size_t grid_voxels = 0;
  // Energy bookkeeping of the removal law (docs/derivations/drilling.md): the work the bur has
  // delivered to the tooth so far [J], and the signed carry of the last removals [J]: a voxel
  // removed with work W against its threshold E_m adds W - E_m. A positive carry (a surplus) is
  // shared by the next tick's set with its own work; a negative one (a debt: a voxel removed at
  // theta E_m <= W < E_m) is paid first from the next ticks' work. No delivered joule is lost or
  // created by the voxel quantum: delivered = sum_m e_m V_m + stored work + carry.
  double delivered_j = 0.0;
  double carry_j = 0.0;

  // Removed volume of material m [m^3].
  double removed_volume_m3(int m) const { return voxel_volume_m3 * removed_voxels[m]; }
};

// Throws InputError unless bur speed and cutting coefficient are finite and >= 0.
void validate_drill_params(const DrillParams& params);

// Solid voxels of `grid` with an empty (or outside) face neighbour: the tooth's surface.
std::size_t count_surface_voxels(const VoxelGrid& grid);

// Entries of the work table of a drill state for a tooth whose surface holds `surface_voxels`:
// twice the surface plus one full contact set (docs/derivations/drilling.md "Storage").
std::size_t drill_work_capacity(std::size_t surface_voxels);

// A zero-work state sized for the tooth / its grid (allocates once): a work table of
// drill_work_capacity(count_surface_voxels(grid)) entries, or of `capacity` if given (> 0).
DrillState make_drill_state(const VoxelGrid& grid, std::size_t capacity = 0);
inline DrillState make_drill_state(const VoxelTooth& tooth) { return make_drill_state(tooth.grid()); }

// The work step of drill_tick, shared with fast/tooth/drilling.h: adds each contact's work W_i to
// its voxel (contact_voxels[i]) in contact order, settling the carry first: a surplus is shared
// by weight on top of the W_i; a debt D takes min(D, sum_i W_i) off the tick's work, every W_i
// scaled by the same factor. Returns false (adding nothing) when the set's
// total weight is not > 0, or when the work table might not hold the set's voxels (then it also
// sets state->work_table_full). Never throws or allocates; the caller validates the arguments.
bool accumulate_drill_work(std::span<const Contact> contacts,
                           std::span<const std::size_t> contact_voxels, const ToolTip& tip,
                           const DrillParams& params, double T, DrillState* state);

// The cut set of the surface-proxy contact models (sdf and field; docs/derivations/drilling.md §5):
// the exposed solid voxels (a face toward empty space: the cut surface) within the bur's cutting
// band, the shell of depth b = kCutBandFraction rho about the bur's sphere (g, rho) at the proxy,
// each weighted by the band's depth at the voxel's middle (cut_band_depth). The power per unit of
// cut surface is then P (b - gap(x)) / (integral of (b - gap) dA): a property of the bur (rho, b),
// not of the grid, so the cut converges as h -> 0 (the voxels sample that density at their middles,
// the midpoint rule). Before issue #30's third change the band was one voxel, b = h (every solid
// voxel meeting the ball of radius rho + h about g, weighted by the cosine to the push): a
// footprint of radius sqrt(2 rho h + h^2) on a flat floor, so the coarse cut was wider and
// shallower, O(h) (§5). Appends one share of `contact` (weight = the band's depth, material = the
// voxel's) and its flat voxel index per voxel, up to the vectors' capacity; `candidates` is
// scratch. Never allocates beyond the vectors' capacity, never throws.
void collect_cut_set(const VoxelTooth& tooth, const Contact& contact, const Vec3& g, double rho,
                     std::vector<std::size_t>* candidates, std::vector<Contact>* shares,
                     std::vector<std::size_t>* voxels);

// The depth of the cutting band (rho, band) at a voxel whose centre lies at squared distance
// `centre_d2` from g, for voxels of edge h: band - gap, gap = sqrt(centre_d2) - rho - h / 2 (the
// bur's distance to the voxel at its middle, 0 if touching head-on, taken as 0 if negative), 0
// outside the band [m]. Inline, with cut_band_depth: the fast twin (fast/tooth/cut_set.cc) sums
// centre_d2 per axis as Eigen's squaredNorm does, (dx^2 + dy^2) + dz^2, and calls this.
inline double cut_band_depth_at(double centre_d2, double rho, double h, double band) {
  const double gap = std::sqrt(centre_d2) - rho - 0.5 * h;
  return std::max(0.0, band - std::max(0.0, gap));
}

// The depth of the cutting band (g, rho, band) at voxel (i, j, k) of `grid` (cut_band_depth_at of
// |centre - g|^2).
inline double cut_band_depth(const VoxelGrid& grid, int i, int j, int k, const Vec3& g, double rho,
                             double band) {
  return cut_band_depth_at((grid.center(i, j, k) - g).squaredNorm(), rho, grid.voxel_size, band);
}

// The depth of the bur's cutting band as a fraction of its radius (collect_cut_set): a model
// constant of the bur like mu_c, b = rho / 3 (0.167 mm for the 0.5 mm bur: the old band h at the
// default 128^3 molar, h = 0.17 mm), so the default grid keeps its footprint and finer grids
// converge to it.
inline constexpr double kCutBandFraction = 1.0 / 3.0;

// The cutting band of a bur of radius rho, as collect_cut_set and its fast twin
// (fast/tooth/cut_set.h) both take it: its depth b = kCutBandFraction rho [m] and its reach
// rho + b [m], the radius of the ball about g whose solid voxels (box nearer than the reach,
// sphere_intersects_voxel) are the cut set's candidates.
struct CutBand {
  double depth;
  double reach;
};
inline CutBand cut_band(double rho) {
  const double b = kCutBandFraction * rho;
  return {b, rho + b};
}

// The removal law's fraction theta (docs/derivations/drilling.md §1): a voxel goes in the first
// tick at whose end its work W satisfies W >= theta E_m, the cut front past its centre; it is
// charged the whole E_m, the missing E_m - W carried as a debt (DrillState::carry_j).
inline constexpr double kRemovalFraction = 0.5;
// The removal test of both twins' drill_tick (one expression, so they agree bitwise).
inline bool removal_due(double work, double threshold) {
  return work >= kRemovalFraction * threshold;
}

// Work charged for removing one voxel of `material` of edge h, E_m = e_m h^3 [J]; throws
// InputError for kEmpty or an unknown id.
double removal_threshold_j(std::uint8_t material, double voxel_size);

// Whether removing voxel (i, j, k) of `grid` (not yet removed) opens the pulp: the voxel is pulp
// or has a pulp face neighbour (DrillState::pulp_exposed; the fast twin shares it).
bool removal_opens_pulp(const VoxelGrid& grid, int i, int j, int k);

// The energy bookkeeping of one voxel of `material` removed with `work` on it against its
// `threshold` (both twins' drill_tick; docs/derivations/drilling.md §2): its work leaves the
// table, W - E_m (a surplus if > 0, a debt if < 0) joins the carry, the material's count rises,
// and its flat index v is appended to `removed` if not null.
void account_removed_voxel(std::size_t v, std::uint8_t material, double work, double threshold,
                           DrillState* state, std::vector<std::size_t>* removed);

// One drilling step after the tick's collision: adds each contact's work to its voxel
// (contact_voxels[i] is contact i's flat voxel index, as returned by collide_tool_tip), then
// removes every contacted voxel whose work reached theta E_m (removal_due). Appends the removed
// flat indices to `removed` if not null and returns their number; the contact set is stale after.
// Throws InputError if the vectors differ in length, T <= 0, or the params are negative.
int drill_tick(std::span<const Contact> contacts, std::span<const std::size_t> contact_voxels,
               const ToolTip& tip, const DrillParams& params, double T, VoxelTooth* tooth,
               DrillState* state, std::vector<std::size_t>* removed = nullptr);

}  // namespace dentsim
