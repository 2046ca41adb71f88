#include "fast/tooth/sdf.h"

namespace dentsim::fast {

// The reference's descent (reference/tooth/sdf.cc), children visited nearest first.
SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach) {
  return sdf_detail::signed_distance_ordered(tooth, x, reach, true);
}

}  // namespace dentsim::fast
