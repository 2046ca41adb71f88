// The "field" contact model (reference/tooth/field_contact.h): the surface proxy on the sampled
// field never crosses a wall one voxel thick (axis-aligned or oblique) whatever the tool's step
// and at the device's peak force, a proxy found inside leaves, the force on a smooth sphere slid
// across is the analytic sphere's within the stated ripple, and the provider's model switch.
#include "reference/tooth/field_contact.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>

#include <Eigen/Geometry>

#include "reference/core/contact_provider.h"
#include "reference/core/io.h"
#include "reference/tooth/tooth_contacts.h"
#include "tooth_io/voxelize.h"
#include "tests/tooth/field_shapes.h"

namespace dentsim {
namespace {

constexpr double kK = 3000.0;      // K_tooth [N/m]
constexpr double kRho = 0.4e-3;    // explorer tip radius [m]
constexpr double kPeakN = 8.5;     // the Phantom Premium 1.5's peak force (crosscheck contact)
constexpr double kSide = 6.4e-3;   // grid edge [m]

using test::box_mesh;

struct Rig {
  VoxelTooth tooth;
  SampledField field;
};

Rig mesh_rig(const TriangleMesh& mesh, int n, int stride = 1) {
  VoxelGrid grid(n, Vec3::Zero(), kSide / n);
  const std::vector<std::uint8_t> in = center_winding_inside(mesh, grid);
  for (std::size_t v = 0; v < in.size(); ++v) grid.voxels[v] = in[v] ? kEnamel : kEmpty;
  SampledField f =
      build_sampled_field(grid, mesh, field_band_for_tip(kRho, grid.voxel_size, stride));
  return {VoxelTooth(std::move(grid)), std::move(f)};
}

// A slab one voxel thick (0.1 mm at 64^3) across the grid, normal n through `mid`.
struct Wall {
  Vec3 n, mid;
  double half;  // half thickness
  double sdf(const Vec3& p) const { return std::abs(n.dot(p - mid)) - half; }
};

TEST(FieldContact, NeverCrossesAWallOneVoxelThickWhateverTheStep) {
  const double h = kSide / 64;
  const Mat3 I = Mat3::Identity();
  const Rig rig = mesh_rig(box_mesh(Vec3(3.2e-3, 0.2e-3, 0.2e-3), Vec3(3.3e-3, 6.2e-3, 6.2e-3), I,
                                    Vec3::Zero()),
                           64);
  ASSERT_NEAR(h, 0.1e-3, 1e-15);
  const FieldSolid solid(rig.tooth, rig.field);
  for (const double step : {0.05e-3, 0.3e-3, 0.9e-3, 3e-3}) {
    SurfaceProxy proxy(kRho, h);
    Vec3 c(2e-3, 3.2e-3, 3.2e-3);
    proxy.update(solid, c);
    for (int tick = 0; tick < 200 && c.x() < 4.6e-3; ++tick) {
      c.x() = std::min(4.6e-3, c.x() + step);
      const Vec3 g = proxy.update(solid, c);
      EXPECT_LE(g.x(), 3.2e-3 - kRho + 1e-9) << "step " << step;
      EXPECT_GE(rig.field.value(g), kRho - proxy.skin());
    }
    // On a flat face the field is the plane's distance (trilinear is exact on a linear
    // function): g rests rho in front of it.
    EXPECT_NEAR(proxy.g().x(), 3.2e-3 - kRho, 1e-9);
  }
}

// Pressed at the device's peak force (quasi-static, as `crosscheck contact`) into a wall one
// voxel thick, axis-aligned and oblique: the rendered centre stays out of {phi < rho - s} and out
// of the source solid, and at rest the wall pushes back the whole force.
void holds_a_thin_wall(int stride) {
  const double h = kSide / 64;
  const Vec3 pivot = Vec3::Constant(0.5 * kSide);
  for (const double angle : {0.0, 0.5, 0.9}) {
    const Mat3 R = Eigen::AngleAxisd(angle, Vec3(0.3, 1.0, 0.6).normalized()).toRotationMatrix();
    Rig rig = mesh_rig(box_mesh(pivot - Vec3(0.5 * h, 2.0e-3, 2.0e-3),
                                pivot + Vec3(0.5 * h, 2.0e-3, 2.0e-3), R, pivot),
                       64, stride);
    ASSERT_EQ(rig.field.stride(), stride);
    const Wall wall{R * Vec3::UnitX(), pivot, 0.5 * h};
    ToothContactProvider provider(const_cast<VoxelTooth&>(rig.tooth), ToolTip{kRho, Vec3::Zero()},
                                  kK, 0.0, nullptr, ContactModel::kField, &signed_distance,
                                  &rig.field);
    std::vector<Contact> contacts;
    contacts.reserve(kContactCapacity);
    const Vec3 d = wall.n;  // push along the normal, into the wall
    Pose pose;
    pose.x = pivot - 1.2e-3 * d + 0.3e-3 * R * Vec3::UnitY();
    double worst = 1.0, worst_source = 1.0;
    Vec3 f = Vec3::Zero();
    for (int tick = 0; tick < 400; ++tick) {
      provider.contacts(pose, contacts);
      f = blended_contact_force(contacts);
      const Vec3 g = provider.surface_proxy().g();
      worst = std::min(worst, rig.field.value(g) - (kRho - provider.surface_proxy().skin()));
      worst_source = std::min(worst_source, wall.sdf(g));
      Vec3 step = 0.5 * (kPeakN * d + f) / kK;
      if (step.norm() > 0.1e-3) step *= 0.1e-3 / step.norm();
      pose.x += step;
    }
    std::printf("angle %.1f: min phi - (rho - s) = %.3g m, min source distance %.3g m, |f| %.3f N\n",
                angle, worst, worst_source, f.norm());
    EXPECT_GE(worst, 0.0) << "angle " << angle;
    EXPECT_GT(worst_source, 0.0) << "angle " << angle;
    EXPECT_LT(wall.n.dot(provider.surface_proxy().g() - pivot), 0.0);  // the near side
    EXPECT_NEAR(-f.dot(d), kPeakN, 0.01 * kPeakN) << "angle " << angle;
  }
}
TEST(FieldContact, HoldsAWallOneVoxelThickAtThePeakForce) { holds_a_thin_wall(1); }
// The spacing rule's wall bound (docs/derivations/field_contact.md §7): every point of the
// source surface has phi <= sqrt(3) H / 2, so a wall of any thickness holds while that is below
// rho - s. At h = 0.1 mm and rho = 0.4 mm the bound admits H < 0.346 mm: stride 3 (H = 0.3 mm,
// sqrt(3) H / 2 = 0.26 mm < rho - s = 0.35 mm), three voxels per sample and the wall one voxel
// thick, so most of the wall holds no sample at all (the field's own solid misses it).
TEST(FieldContact, HoldsAWallOneVoxelThickAtThePeakForceAtTheLargestStrideTheBoundAdmits) {
  ASSERT_LT(3 * 0.1e-3, 2.0 * 0.75 * kRho / std::sqrt(3.0));  // H_wall (s <= rho / 4)
  ASSERT_LT(std::sqrt(3.0) * 0.3e-3 / 2.0, kRho - 0.05e-3);
  holds_a_thin_wall(3);
}

// The spacing rule itself: H_max = min(0.866 rho, 0.357 rho), and the strides it gives.
TEST(FieldContact, SpacingRuleGivesTheLargestAdmissibleStride) {
  EXPECT_NEAR(field_max_spacing(kRho), kRho * kFieldRippleAim / kFieldRipplePerSpacing, 1e-18);
  EXPECT_NEAR(field_max_spacing(kRho) / kRho, 0.35714, 1e-5);
  EXPECT_EQ(field_stride_for(kRho, 0.05e-3), 2);       // 0.143 mm / 0.05 mm
  EXPECT_EQ(field_stride_for(kRho, 0.1734e-3), 1);     // never below one voxel
  EXPECT_EQ(field_stride_for(0.5e-3, 0.02e-3), 8);     // 0.179 mm / 0.02 mm
  EXPECT_EQ(field_stride_for(kRho, 0.05e-3, 0.15e-3), 3);  // an exact multiple, whatever rounding
  EXPECT_EQ(field_stride_for(kRho, 0.05e-3, 0.149e-3), 2);
  EXPECT_EQ(field_stride_for(kRho, 0.05e-3, 0.05e-3), 1);
}

TEST(FieldContact, ProxyFoundInsideLeavesAlongTheShortestWay) {
  const Rig rig = mesh_rig(box_mesh(Vec3(1e-3, 1e-3, 1e-3), Vec3(5e-3, 5e-3, 3e-3),
                                    Mat3::Identity(), Vec3::Zero()),
                           64);
  const FieldSolid solid(rig.tooth, rig.field);
  SurfaceProxy proxy(kRho, rig.tooth.grid().voxel_size);
  // 0.8 mm below the top face (z = 3 mm), deep inside: out through the top.
  const Vec3 g = proxy.update(solid, Vec3(3.1e-3, 2.9e-3, 2.2e-3));
  EXPECT_NEAR(g.z(), 3e-3 + kRho, 1e-9);
  EXPECT_NEAR(g.x(), 3.1e-3, 1e-9);
  EXPECT_NEAR(g.y(), 2.9e-3, 1e-9);
}

// A sphere of radius 2.5 mm from its implicit function at h = 0.05 mm, pressed at 1 N and led
// along a meridian (as `crosscheck contact`'s sliding ripple): the force is the analytic sphere's
// K (R + rho - |c|) u within 2 % RMS of F (measured 0.63 %; the sdf model's staircase gives
// 17 % here).
// The sliding ripple on a sphere at 1 N (field and sdf) with the field at `stride`.
void sphere_ripple(int stride, double ripple[2]) {
  const double r = 2.5e-3, h = 0.05e-3;
  const int n = 128;
  VoxelGrid grid(n, Vec3::Zero(), h);
  const Vec3 centre = Vec3::Constant(0.5 * n * h);
  const auto inside = [&](const Vec3& p) { return (p - centre).norm() < r; };
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (inside(grid.center(i, j, k))) grid.set(i, j, k, kEnamel);
      }
    }
  }
  SampledField field = build_sampled_field(grid, triangulate_implicit(grid, inside),
                                           field_band_for_tip(kRho, h, stride));
  VoxelTooth tooth(std::move(grid));
  for (const ContactModel model : {ContactModel::kField, ContactModel::kSurfaceProxy}) {
    ToothContactProvider provider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, nullptr, model,
                                  &signed_distance, &field);
    std::vector<Contact> contacts;
    contacts.reserve(kContactCapacity);
    const double force = 1.0, azimuth = 20.0 * std::numbers::pi / 180.0;
    const double radius = r + kRho - force / kK;
    double sum2 = 0.0;
    const int ticks = 800;
    for (int i = 0; i < ticks; ++i) {
      const double polar = (80.0 * std::numbers::pi / 180.0) * i / (ticks - 1);
      const Vec3 u(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                   std::cos(polar));
      Pose pose;
      pose.x = centre + radius * u;
      provider.contacts(pose, contacts);
      sum2 += (blended_contact_force(contacts) - force * u).squaredNorm() / (force * force);
    }
    ripple[model == ContactModel::kField ? 0 : 1] = std::sqrt(sum2 / ticks);
  }
  std::printf("sliding ripple at 1 N, R = 2.5 mm, h = 0.05 mm, stride %d: field %.4f, sdf %.4f\n",
              stride, ripple[0], ripple[1]);
}

TEST(FieldContact, SlidingOnASmoothSphereHasLittleRipple) {
  double ripple[2] = {0.0, 0.0};
  sphere_ripple(1, ripple);
  EXPECT_LT(ripple[0], 0.02);
  EXPECT_LT(ripple[0], 0.25 * ripple[1]);
}

// The ripple bound of the spacing rule (docs/derivations/field_contact.md §7): ripple <=
// c_ripple H / rho, at the automatic stride (2: H = 0.1 mm) and one beyond it (3), so the
// automatic spacing keeps the aim of 2 %.
TEST(FieldContact, SlidingRippleOnASphereStaysWithinTheSpacingRulesBound) {
  const double h = 0.05e-3;
  ASSERT_EQ(field_stride_for(kRho, h), 2);
  for (const int stride : {2, 3}) {
    double ripple[2] = {0.0, 0.0};
    sphere_ripple(stride, ripple);
    EXPECT_LT(ripple[0], kFieldRipplePerSpacing * stride * h / kRho) << "stride " << stride;
    EXPECT_LT(ripple[0], 0.25 * ripple[1]) << "stride " << stride;
    if (stride == 2) {
      EXPECT_LT(ripple[0], kFieldRippleAim);
    }
  }
}

TEST(FieldContact, ModelNameAndRefusals) {
  EXPECT_EQ(parse_contact_model("field"), ContactModel::kField);
  EXPECT_STREQ(contact_model_name(ContactModel::kField), "field");
  VoxelTooth tooth(VoxelGrid(16, Vec3::Zero(), 1e-4));
  EXPECT_THROW(ToothContactProvider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, nullptr,
                                    ContactModel::kField),
               InputError);
  SampledField field;
  DrillParams drill;
  drill.bur_speed_rad_s = 100.0;
  // Drilling on the field is accepted (the field follows the cut, field_drilling_test.cc).
  EXPECT_NO_THROW(ToothContactProvider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, &drill,
                                       ContactModel::kField, &signed_distance, &field));
}

}  // namespace
}  // namespace dentsim
