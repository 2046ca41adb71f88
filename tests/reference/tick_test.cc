// Tests for reference/tick.h (part 9 of the reference pipeline): the servo tick composing the
// kinematics, observer, collision, proxy solve, coupling and decomposition, run in closed loop
// with the rigid-body device and a flat wall (validation/wall_loop.h).
#include "reference/tick.h"

#include <gtest/gtest.h>

#include <cmath>

#include "reference/core/so3.h"
#include "reference/rigid_body_device.h"
#include "reference/tools.h"
#include "validation/wall_loop.h"

namespace dentsim {
namespace {

// The same testbed for every method: only the method switch changes.
WallLoopConfig testbed(Method m, double k_vc, double k_tooth, double push_n) {
  WallLoopConfig c;
  c.device.mass = 0.075;
  c.device.inertia = Mat3::Identity() * 2e-4;
  c.device.damping_lin = 0.5;
  c.device.damping_ang = 0.002;
  c.pipeline.method = m;
  c.pipeline.proxy.mass = 0.02;
  c.pipeline.proxy.inertia = Mat3::Identity() * 2e-6;
  c.pipeline.coupling.k_lin = k_vc;
  c.pipeline.coupling.b_lin = 0.05;
  c.pipeline.coupling.k_ang = 0.3;
  c.pipeline.coupling.b_ang = 1e-4;
  c.pipeline.tool = tool_preset("handpiece");
  c.pipeline.observer_gain = VecX::Constant(6, 100.0);
  c.wall_stiffness = k_tooth;
  // A hand that is a force source with a little damping (no spring pulling it back), so at rest
  // the force fed back must equal the push.
  c.hand.stiffness = 0.0;
  c.hand.damping = 2.0;
  c.hand.push = Vec3(0, 0, -push_n);
  c.start = Vec3(0, 0, c.tip_radius + 2e-4);
  c.duration = 2.0;
  return c;
}

TEST(Tick, AtRestWithNoContactCommandsNothing) {
  const RigidBodyDevice dev;
  PipelineConfig cfg;
  ReferencePipeline p(dev, cfg);
  DeviceSample s;
  s.q = dev.joint_position(Pose{Vec3(0.01, -0.02, 0.03), exp_so3(Vec3(0.2, -0.1, 0.3))});
  s.qd = VecX::Zero(6);
  p.reset(s);
  NoContacts none;
  for (int k = 0; k < 10; ++k) {
    s.t = k * 1e-3;
    const TickResult& r = p.tick(s, 1e-3, none);
    EXPECT_LT(r.tau.norm(), 1e-12);
    EXPECT_LT((p.proxy().pose.x - Vec3(0.01, -0.02, 0.03)).norm(), 1e-15);
  }
}

TEST(Tick, CouplingActsEquallyAndOppositelyOnDeviceAndProxy) {
  // Device displaced from a resting proxy: the device-side wrench (4.3)-(4.4) and the proxy-side
  // spring (4.5) at t_k are opposite; tau = J1^-T T1 gives back T1 through J1^T.
  const RigidBodyDevice dev;
  PipelineConfig cfg;
  cfg.coupling.b_lin = 0.0;
  cfg.coupling.b_ang = 0.0;
  ReferencePipeline p(dev, cfg);
  DeviceSample s;
  s.q = dev.joint_position(Pose{Vec3::Zero(), Mat3::Identity()});
  s.qd = VecX::Zero(6);
  p.reset(s);
  s.q = dev.joint_position(Pose{Vec3(0.002, 0.0, -0.001), Mat3::Identity()});
  NoContacts none;
  const TickResult& r = p.tick(s, 1e-3, none);
  EXPECT_NEAR(r.T1(0), -cfg.coupling.k_lin * 0.002, 1e-12);
  EXPECT_NEAR(r.T1(2), cfg.coupling.k_lin * 0.001, 1e-12);
  const Mat6 J1 = dev.twist_to_joint(s.q);
  EXPECT_LT((J1.transpose() * r.tau - r.T1).norm(), 1e-12);
  // The proxy is pulled toward the device, the device toward the proxy.
  EXPECT_GT(r.F_coupling(0), 0.0);
  EXPECT_LT(r.T1(0), 0.0);
}

TEST(Tick, FreeSpaceProxyFollowsTheDevice) {
  WallLoopConfig c = testbed(Method::kPmiVc, 400, 1500, 0.0);
  c.wall_point = Vec3(0, 0, -1.0);  // far away: no contact
  c.hand.travel = 0.02;
  c.hand.speed = 0.05;
  c.duration = 1.0;
  const WallLoopResult r = run_wall_loop(c);
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(r.contact_ticks, 0);
  EXPECT_LT(r.max_force_n, 0.2);  // only the proxy's inertia and the coupling damper are felt
}

// Static rendered stiffness: with PMI virtual coupling the device sees the coupling and the wall
// in series (thesis §3.1, Fig. 3.1): K = K_vc K_tooth / (K_vc + K_tooth).
TEST(Tick, PmiCouplingRendersSeriesStiffnessAtRest) {
  const double k_vc = 400, k_tooth = 1500, push = 1.0;
  const WallLoopResult r = run_wall_loop(testbed(Method::kPmiVc, k_vc, k_tooth, push));
  ASSERT_TRUE(r.finite);
  ASSERT_GT(r.contact_ticks, 500);
  const double expected = k_vc * k_tooth / (k_vc + k_tooth);
  EXPECT_NEAR(r.final_force_n, push, 0.02 * push);
  EXPECT_NEAR(r.final_force_n / r.final_device_depth_m, expected, 0.03 * expected);
}

// With passive decomposition the feed-forward cancels the human force estimate, the coupling
// spring is unloaded at rest and the device feels the wall itself: K -> K_tooth.
TEST(Tick, PassiveDecompositionRendersTheWallStiffnessAtRest) {
  const double k_vc = 400, k_tooth = 1500, push = 1.0;
  const WallLoopResult r = run_wall_loop(testbed(Method::kPmiPd, k_vc, k_tooth, push));
  ASSERT_TRUE(r.finite);
  ASSERT_GT(r.contact_ticks, 500);
  EXPECT_NEAR(r.final_force_n, push, 0.05 * push);
  EXPECT_NEAR(r.final_force_n / r.final_device_depth_m, k_tooth, 0.05 * k_tooth);
}

// A stiff wall under a light proxy (omega T = sqrt(K_tooth / m) T = 1): explicit Euler produces
// energy and goes unstable, PMI stays passive. K_vc respects the device-side passivity bound of
// the coupling, b_d >= 2 b_vc + K_vc T (thesis §3.1), for both.
TEST(Tick, ExplicitGainsEnergyWherePmiStaysPassive) {
  const double k_vc = 300, k_tooth = 20000, push = 1.0;
  const WallLoopResult pmi = run_wall_loop(testbed(Method::kPmiVc, k_vc, k_tooth, push));
  const WallLoopResult exp = run_wall_loop(testbed(Method::kExplicitVc, k_vc, k_tooth, push));
  ASSERT_TRUE(pmi.finite);
  EXPECT_LE(pmi.energy_virtual_j, 1e-6);
  // Explicit: the virtual side pumps energy into the device (or the loop blows up).
  EXPECT_TRUE(!exp.finite || exp.max_energy_virtual_j > 1e-3)
      << "explicit E_v max " << exp.max_energy_virtual_j;
}

TEST(Tick, TorqueSaturatesUniformly) {
  const RigidBodyDevice dev;
  PipelineConfig cfg;
  cfg.torque_limit = VecX::Constant(6, 0.1);
  ReferencePipeline p(dev, cfg);
  DeviceSample s;
  s.q = VecX::Zero(6);
  s.qd = VecX::Zero(6);
  p.reset(s);
  s.q(0) = 0.01;  // 4 N of coupling force on joint 0, far beyond 0.1
  s.q(1) = 0.005;
  NoContacts none;
  const TickResult& r = p.tick(s, 1e-3, none);
  EXPECT_TRUE(r.saturated);
  EXPECT_NEAR(r.tau.cwiseAbs().maxCoeff(), 0.1, 1e-15);
  // Direction kept: the ratio of the two loaded joints is that of the unsaturated wrench.
  EXPECT_NEAR(r.tau(0) / r.tau(1), r.T1(0) / r.T1(1), 1e-12);
}

TEST(Tick, PmiPdWithoutObserverGainIsRejected) {
  const RigidBodyDevice dev;
  PipelineConfig cfg;
  cfg.method = Method::kPmiPd;
  EXPECT_THROW(ReferencePipeline(dev, cfg), std::invalid_argument);
  cfg.observer_gain = VecX::Constant(3, 50.0);
  EXPECT_THROW(ReferencePipeline(dev, cfg), std::invalid_argument);
}

TEST(Tick, RejectsNonPositiveTick) {
  const RigidBodyDevice dev;
  ReferencePipeline p(dev, PipelineConfig{});
  DeviceSample s;
  s.q = VecX::Zero(6);
  s.qd = VecX::Zero(6);
  p.reset(s);
  NoContacts none;
  EXPECT_THROW(p.tick(s, 0.0, none), std::invalid_argument);
  EXPECT_THROW(p.tick(s, std::nan(""), none), std::invalid_argument);
}

}  // namespace
}  // namespace dentsim
