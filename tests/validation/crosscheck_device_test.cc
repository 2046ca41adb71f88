// The analytic Phantom model against MuJoCo 2.2.2 (validation/crosscheck_device.h) and `dentsim
// crosscheck device --json` (the MJCF generator itself: tests/plant/phantom_mjcf_test.cc).
// Tolerance policy (docs/phantom.md): static quantities agree to 1e-9 relative (max-norm of the
// difference over max-norm of the reference; measured ~1e-14); each reference is guarded to be
// a real signal; the 1 s trajectory (Coulomb-free, both models gravity-compensated) diverges by
// less than 1e-6 rad while the device moves more than 0.5 rad.
#include "validation/crosscheck_device.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>

#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

TEST(CrosscheckDevice, ThousandRandomStatesAgreeToRoundOff) {
  DeviceCrosscheckOptions o;
  o.samples = 1000;
  std::printf("seed %llu; re-run: dentsim crosscheck device --seed %llu\n",
              static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed));
  const DeviceCrosscheckResult r = crosscheck_device(default_phantom_params(), o);
  std::printf("%s\n", crosscheck_device_json(r).dump(2).c_str());
  EXPECT_EQ(r.samples, 1000);
  for (const auto* e : {&r.mass_matrix, &r.bias, &r.gravity, &r.pose, &r.jacobian}) {
    EXPECT_LT(e->max_rel, 1e-9);
  }
  // Guards: the compared quantities carry real signal.
  EXPECT_GT(r.mass_matrix.max_ref, 1e-3);  // kg m^2
  EXPECT_GT(r.bias.max_ref, 1e-2);         // N m at |qd| <= 3 rad/s
  EXPECT_GT(r.gravity.max_ref, 0.1);       // N m
  EXPECT_GT(r.jacobian.max_ref, 0.5);
  // Trajectory: tight agreement while the device really moves.
  EXPECT_GT(r.trajectory_range_rad, 0.5);
  EXPECT_LT(r.trajectory_max_abs_rad, 1e-6);
  EXPECT_LT(r.trajectory_max_closure_rad, 1e-6);
  // With Coulomb friction the laws differ (soft frictionloss vs tanh): reported, loosely bounded.
  EXPECT_LT(r.trajectory_coulomb_max_abs_rad, 1.0);
}

// Random device models (gimbal axes and offsets, CoMs, masses, inertias, tip, lengths): the
// generator and the analytic tree agree for any geometry, not only the axis-aligned default.
// Short form 5 models x 200 states; DENTSIM_STRESS=full: 100 models x 1000 states.
TEST(CrosscheckDeviceStress, RandomDeviceModelsAgreeToRoundOff) {
  const std::uint64_t seed = 777;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto unit = [&] {
    Vec3 a(u(rng), u(rng), u(rng));
    return Vec3(a / a.norm());
  };
  auto body = [&](PhantomBody b) {
    b.mass_kg *= 1.0 + 0.3 * u(rng);
    b.com_m += 0.01 * Vec3(u(rng), u(rng), u(rng));
    // Moments of a solid ellipsoid with random semi-axes: always a physical inertia.
    const Vec3 ax = 0.02 * (Vec3(u(rng), u(rng), u(rng)).cwiseAbs() + Vec3::Constant(0.2));
    const double k = b.mass_kg / 5.0;
    b.inertia_kg_m2 = k * Vec3(ax(1) * ax(1) + ax(2) * ax(2), ax(0) * ax(0) + ax(2) * ax(2),
                               ax(0) * ax(0) + ax(1) * ax(1));
    return b;
  };
  const int models = static_cast<int>(testing::stress_count(5, 100));
  DeviceCrosscheckOptions o;
  o.samples = static_cast<int>(testing::stress_count(200, 1000));
  o.trajectory_s = 0.0;  // static quantities only
  double worst = 0.0;
  for (int n = 0; n < models; ++n) {
    PhantomParams p = default_phantom_params();
    p.l1_m *= 1.0 + 0.2 * u(rng);
    p.l2_m *= 1.0 + 0.2 * u(rng);
    p.l3_m *= 1.0 + 0.2 * u(rng);
    for (PhantomBody* b : {&p.base, &p.upper_arm, &p.forearm, &p.crank, &p.parallel_link,
                           &p.gimbal_yaw, &p.gimbal_pitch, &p.gimbal_roll}) {
      *b = body(*b);
    }
    p.yaw_axis = unit();
    p.pitch_axis = unit();
    p.roll_axis = unit();
    p.pitch_pos_m = 0.02 * Vec3(u(rng), u(rng), u(rng));
    p.roll_pos_m = 0.02 * Vec3(u(rng), u(rng), u(rng));
    p.tip_offset_m = 0.05 * Vec3(u(rng), u(rng), u(rng));
    for (int j = 0; j < 6; ++j) p.armature_kg_m2(j) *= 1.0 + 0.5 * u(rng);
    validate_phantom_params(p, "random model " + std::to_string(n));
    o.seed = seed + n;
    const DeviceCrosscheckResult r = crosscheck_device(p, o);
    for (const auto* e : {&r.mass_matrix, &r.bias, &r.gravity, &r.pose, &r.jacobian}) {
      worst = std::max(worst, e->max_rel);
      EXPECT_LT(e->max_rel, 1e-9) << "model " << n;
    }
  }
  std::printf("%d random models: worst max_rel %.3e\n", models, worst);
}

TEST(CrosscheckDeviceCli, WritesTheContractJson) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("dentsim_xcheck_" + std::to_string(::getpid()) + ".json"))
                               .string();
  const std::string cmd =
      std::string(DENTSIM_BINARY) + " crosscheck device --samples 1000 --json " + path;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const nlohmann::json j = nlohmann::json::parse(read_file(path));
  for (const char* key : {"mass_matrix", "bias", "gravity", "pose", "jacobian"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_LT(j[key]["max_rel"].get<double>(), 1e-9) << key;
    EXPECT_GE(j[key]["max_abs"].get<double>(), 0.0) << key;
  }
  EXPECT_LT(j["trajectory"]["max_abs_rad"].get<double>(), 1e-6);
  EXPECT_EQ(j["samples"].get<int>(), 1000);
  std::filesystem::remove(path);
  // Bad model file: exit status 2.
  const std::string bad =
      std::string(DENTSIM_BINARY) + " crosscheck device --model /nonexistent.json 2>/dev/null";
  const int st = std::system(bad.c_str());
  EXPECT_EQ(WEXITSTATUS(st), 2);
}

}  // namespace
}  // namespace dentsim
