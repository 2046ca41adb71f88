// Fast drilling of the voxel tooth: the twin of reference/tooth/drilling.h (thesis §2.5.2
// "Drilling"; the work model W_i = mu_c f_i omega rho T_k and the thresholds are stated there and
// in docs/tooth_octree.md). Same work per voxel summed in the same order (the shared
// accumulate_drill_work, carry included), same removal test (removal_due) and order, so the
// removed voxel sets, the codes and the removed volume per material equal the reference's bitwise.
// Removal updates the fast tooth incrementally (BrickTooth::remove_voxel: the exposed-face bit
// toward the removed voxel in each solid neighbour, surface masks and the brick octree).
// Runs inside the servo tick: never allocates (beyond `removed`'s capacity) and never throws.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "fast/tooth/brick_tooth.h"
#include "reference/core/params.h"
#include "reference/tooth/drilling.h"

namespace dentsim::fast {

// The drill state is the reference's (make_drill_state(tooth.grid()), reference/tooth/drilling.h).

// The twin of dentsim::drill_tick. Where the reference throws InputError (vectors of different
// length, T not finite and > 0, negative params, a state of another size) this returns 0 and
// changes nothing: the tick must not throw, and the provider validates the params when built.
int drill_tick(std::span<const Contact> contacts, std::span<const std::size_t> contact_voxels,
               const ToolTip& tip, const DrillParams& params, double T, BrickTooth* tooth,
               DrillState* state, std::vector<std::size_t>* removed = nullptr);

}  // namespace dentsim::fast
