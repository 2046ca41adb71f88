// The simulated Phantom built from the device model file (device/phantom_device.h): the plant's
// wiring (tree map, device dofs, tip) against the analytic model, and the device effects on the
// real mechanism.
#include "device/phantom_device.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>

#include "plant/mujoco_plant.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

TEST(PhantomDevice, PlantAgreesWithTheAnalyticModel) {
  const PhantomParams p = default_phantom_params();
  const MujocoPlant plant = phantom_plant(p);
  const MujocoDeviceModel sim_model(plant);
  const PhantomModel model(p);
  VecX q = phantom_home_q(p);
  q += VecX::LinSpaced(6, -0.1, 0.15);
  VecX qd = VecX::LinSpaced(6, 0.3, -0.4);
  const double dM = (sim_model.mass_matrix(q) - model.mass_matrix(q)).cwiseAbs().maxCoeff();
  const double dg = (sim_model.gravity(q) - model.gravity(q)).cwiseAbs().maxCoeff();
  const double dC = (sim_model.coriolis_matrix(q, qd) * qd - model.coriolis_matrix(q, qd) * qd)
                        .cwiseAbs()
                        .maxCoeff();
  std::printf("MuJoCo plant vs analytic: |dM| %.2e, |dg| %.2e, |dC qd| %.2e\n", dM, dg, dC);
  EXPECT_LT(dM, 1e-10);
  EXPECT_LT(dg, 1e-10);
  EXPECT_LT(dC, 1e-7);  // C by central differences of M in the MuJoCo model
  // Tip: the simulated device's tip is the model's forward kinematics.
  SimulatedPhantom dev(plant, phantom_device_config(p), q);
  const Pose a = dev.tip_pose(), b = model.forward_kinematics(q);
  EXPECT_LT((a.x - b.x).norm(), 1e-12);
  EXPECT_LT((a.R - b.R).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(PhantomDevice, QuantumFromTheModelFileIsTheEncoderResolution) {
  const PhantomParams p = default_phantom_params();
  SimulatedPhantom dev(phantom_plant(p), phantom_device_config(p), phantom_home_q(p));
  const double ratio[3] = {13.3, 11.2, 11.2};
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(dev.quantum()[j], 2 * std::numbers::pi / (4 * 1024 * ratio[j]), 1e-15);
  }
  // Released under gravity (no motor torque), every measured angle is a whole number of quanta.
  DeviceSample s = dev.make_sample();
  for (int k = 0; k < 50; ++k) {
    dev.write(VecX::Zero(6));
    dev.advance();
    dev.read(s);
    for (int j = 0; j < 6; ++j) {
      const double c = s.q[j] / dev.quantum()[j];
      ASSERT_NEAR(c, std::round(c), 1e-6) << "joint " << j;
    }
  }
  EXPECT_GT((s.q - phantom_home_q(p)).cwiseAbs().maxCoeff(), 10 * dev.quantum()[1]);
}

TEST(PhantomDevice, WithoutGravityAndTorqueItStaysStill) {
  const PhantomParams p = default_phantom_params();
  SimulatedDeviceConfig c = phantom_device_config(p);
  c.gravity = false;
  const VecX q0 = phantom_home_q(p);
  SimulatedPhantom dev(phantom_plant(p), c, q0);
  DeviceSample s0 = dev.make_sample(), s = dev.make_sample();
  dev.read(s0);
  for (int k = 0; k < 1000; ++k) {
    dev.write(VecX::Zero(6));
    dev.advance();
  }
  dev.read(s);
  const double drift = (dev.true_q() - q0).cwiseAbs().maxCoeff();
  std::printf("Phantom, gravity off, 1 s: max |q - q0| = %.3e rad\n", drift);
  EXPECT_EQ(s.q, s0.q);
  EXPECT_EQ(s.qd, VecX::Zero(6));
  EXPECT_LT(drift, 1e-12);
}

TEST(PhantomDevice, GravityCompensatedHandForceBalancesAtRest) {
  // Motors render g(q) from the analytic model; the hand holds a reference 5 mm away; the device
  // settles (no stiction: friction off) where the hand's spring force vanishes, i.e. at x_ref.
  const PhantomParams p = default_phantom_params();
  SimulatedDeviceConfig c = phantom_device_config(p);
  c.friction_on = false;
  c.quantize = false;
  SimulatedPhantom dev(phantom_plant(p), c, phantom_home_q(p));
  const PhantomModel model(p);
  HandKeyframe k;
  k.x_ref = dev.tip_pose().x + Vec3(0.003, -0.002, 0.004);
  const ScriptedHand hand(HandImpedance{}, {k}, dev.tip_pose().R);
  dev.set_hand(&hand);
  for (int i = 0; i < 4000; ++i) {
    dev.write(model.gravity(dev.true_q()));
    dev.advance();
  }
  const double miss = (dev.tip_pose().x - k.x_ref).norm();
  std::printf("Phantom + hand at rest: |x - x_ref| = %.3e m, |F_hand| = %.3e\n", miss,
              dev.hand_wrench().norm());
  EXPECT_LT(miss, 1e-6);
  EXPECT_LT(dev.hand_joint_torque().norm(), 1e-5);
}

}  // namespace
}  // namespace dentsim
