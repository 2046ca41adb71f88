// Differential helpers for the fast tooth (tests/fast/tooth_*_test.cc): the reference and the
// fast contact set of one pose, compared member by member, and seeded random poses near the
// tooth's surface.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <random>
#include <string>
#include <vector>

#include "fast/tooth/collision.h"
#include "reference/core/so3.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/drilling.h"
#include "tests/support/random.h"

namespace dentsim::testing {

constexpr double kToothK = 3000.0;  // K_tooth [N/m]
constexpr double kToothB = 5.0;     // B_tooth [N s/m]

// Drill params that cut ~20x faster than the default (mu_c = 10): on the coarse test grids a
// 1000-tick run then removes hundreds of voxels of every material it reaches.
inline DrillParams fast_cutting() {
  DrillParams p;
  p.cutting_coefficient = 10.0;
  return p;
}

struct ContactSet {
  std::vector<Contact> contacts;
  std::vector<std::size_t> voxels;
  bool complete = true;
};

inline ContactSet reference_set(const VoxelTooth& tooth, const Pose& pose, const ToolTip& tip,
                                std::size_t max_contacts = 1u << 20) {
  ContactSet s;
  CollisionScratch scratch;
  s.complete = collide_tool_tip(tooth, pose, tip, kToothK, kToothB, &scratch, &s.contacts,
                                &s.voxels, max_contacts);
  return s;
}

inline ContactSet fast_set(const fast::BrickTooth& tooth, const Pose& pose, const ToolTip& tip,
                           std::size_t max_contacts = 1u << 20) {
  ContactSet s;
  s.complete = fast::collide_tool_tip(tooth, pose, tip, kToothK, kToothB, &s.contacts, &s.voxels,
                                      max_contacts);
  return s;
}

// Exact equality (tolerance policy 1: integer results; the doubles come from the same
// expressions in the same order, so they are compared bitwise too). Returns true when equal;
// otherwise adds one failure naming the first differing member and `what`.
inline bool same_set(const ContactSet& ref, const ContactSet& fst, const std::string& what) {
  if (ref.complete != fst.complete || ref.contacts.size() != fst.contacts.size() ||
      ref.voxels != fst.voxels) {
    ADD_FAILURE() << what << ": reference " << ref.contacts.size() << " contacts (complete "
                  << ref.complete << "), fast " << fst.contacts.size() << " (complete "
                  << fst.complete << ") or voxel indices differ";
    return false;
  }
  for (std::size_t m = 0; m < ref.contacts.size(); ++m) {
    const Contact& a = ref.contacts[m];
    const Contact& b = fst.contacts[m];
    if (a.n != b.n || a.x_o != b.x_o || a.r != b.r || a.depth != b.depth ||
        a.stiffness != b.stiffness || a.damping != b.damping || a.weight != b.weight ||
        a.material != b.material) {
      ADD_FAILURE() << what << ": member " << m << " (voxel " << ref.voxels[m]
                    << ") differs: depth " << a.depth << " vs " << b.depth << ", weight "
                    << a.weight << " vs " << b.weight << ", n " << a.n.transpose() << " vs "
                    << b.n.transpose() << ", x_o " << a.x_o.transpose() << " vs "
                    << b.x_o.transpose();
      return false;
    }
  }
  return true;
}

// Flat indices of the surface voxels (nonzero code) of a tooth.
inline std::vector<std::size_t> surface_voxels_of(const NeighborCodes& codes) {
  std::vector<std::size_t> out;
  for (std::size_t v = 0; v < codes.code.size(); ++v) {
    if (codes.code[v] != 0) out.push_back(v);
  }
  return out;
}

// A random pose whose tip (radius rho, random body offset) is centred within rho + 2 h of the
// centre of a random surface voxel, with a random rotation.
inline Pose random_pose_near(const VoxelGrid& grid, const std::vector<std::size_t>& surface,
                             double rho, const Vec3& offset_body, std::mt19937& rng) {
  std::uniform_int_distribution<std::size_t> pick(0, surface.size() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const std::size_t v = surface[pick(rng)];
  const int n = grid.n;
  const Vec3 centre = grid.center(static_cast<int>(v % n), static_cast<int>((v / n) % n),
                                  static_cast<int>(v / (static_cast<std::size_t>(n) * n)));
  const double spread = rho + 2.0 * grid.voxel_size;
  const Vec3 c = centre + spread * Vec3(unit(rng), unit(rng), unit(rng));
  Pose pose;
  pose.R = exp_so3(3.0 * unit(rng) * random_unit(rng));
  pose.x = c - pose.R * offset_body;
  return pose;
}

// A drilling bur over the molar's crown: the tip wanders on a seeded random walk in x, y (steps up
// to 0.3 voxel, kept within `range` of the start column) and presses `press` below the current
// top surface of its column (read from the grid it is cutting), with a small random rotation, so
// it keeps cutting through enamel into dentin.
class DrillPath {
 public:
  DrillPath(const VoxelGrid& g, double rho, double range, std::uint64_t seed)
      : rng_(seed), rho_(rho), range_(range) {
    start_ = g.center(g.n / 2, g.n / 2, 0);
    pose_.x = start_;
  }
  const Pose& next(const VoxelGrid& g, const Vec3& offset_body = Vec3::Zero()) {
    const double h = g.voxel_size;
    Vec3 c = pose_.x + pose_.R * offset_body;
    for (int a = 0; a < 2; ++a) {
      c[a] = std::clamp(c[a] + 0.3 * h * unit_(rng_), start_[a] - range_, start_[a] + range_);
    }
    const int i = static_cast<int>((c.x() - g.origin.x()) / h);
    const int j = static_cast<int>((c.y() - g.origin.y()) / h);
    double top = g.origin.z();
    for (int k = 0; k < g.n; ++k) {
      if (g.solid(i, j, k)) top = g.origin.z() + h * (k + 1);
    }
    c.z() = top + rho_ * (0.7 + 0.2 * unit_(rng_));
    pose_.R = exp_so3(0.2 * Vec3(unit_(rng_), unit_(rng_), unit_(rng_)));
    pose_.x = c - pose_.R * offset_body;
    return pose_;
  }

 private:
  std::mt19937 rng_;
  std::uniform_real_distribution<double> unit_{-1.0, 1.0};
  double rho_, range_;
  Vec3 start_;
  Pose pose_;
};

}  // namespace dentsim::testing
