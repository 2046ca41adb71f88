// Tests for reference/tick.h (part 9 of the reference pipeline): the servo tick composing the
// kinematics, observer, collision, proxy solve, coupling and decomposition, run in closed loop
// with the rigid-body device and a flat wall (validation/wall_loop.h).
#include "reference/tick.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "reference/core/so3.h"
#include "reference/grasp_mass_model.h"
#include "reference/rigid_body_device.h"
#include "reference/tick_detail.h"
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

// detail::all_finite (the device stage's and the fast PMI solve's finite check) gives
// allFinite()'s answer: for each non-finite value (+inf, -inf, NaN) in each entry of a 6x6 and a
// 3-vector, alone or beside the largest and smallest doubles and signed zeros, and for finite
// extremes (no overflow: x * 0 is a zero for every finite x).
TEST(Tick, AllFiniteAgreesWithEigensAllFinite) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double bad[] = {kInf, -kInf, std::numeric_limits<double>::quiet_NaN()};
  const double good[] = {0.0, -0.0, std::numeric_limits<double>::max(),
                         -std::numeric_limits<double>::max(),
                         std::numeric_limits<double>::denorm_min(), 1.0};
  int checked = 0;
  for (const double fill : good) {
    Mat6 A = Mat6::Constant(fill);
    Vec3 v = Vec3::Constant(-fill);
    ASSERT_TRUE(A.allFinite() && v.allFinite());
    EXPECT_TRUE(reference::detail::all_finite(A, v));
    EXPECT_TRUE(reference::detail::all_finite(A));
    for (const double b : bad) {
      for (int i = 0; i < 36; ++i) {
        Mat6 Ab = A;
        Ab(i) = b;
        EXPECT_EQ(reference::detail::all_finite(Ab, v), Ab.allFinite() && v.allFinite());
        EXPECT_FALSE(reference::detail::all_finite(v, Ab));
        ++checked;
      }
      for (int i = 0; i < 3; ++i) {
        Vec3 vb = v;
        vb(i) = b;
        EXPECT_FALSE(reference::detail::all_finite(A, vb));
        EXPECT_EQ(reference::detail::all_finite(vb), vb.allFinite());
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 6 * 3 * 39);
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

// The pipeline with a grip detector (reference/grip_detector.h) whose state never changes is the
// pipeline on the model of that state: stuck "gripped" it is the pipeline on the grasp model,
// stuck "released" the one on the device alone (same commanded torques, tick by tick, on a
// moving device pressed into a wall).
TEST(Tick, GripDetectorStuckInOneStateIsThePipelineOnThatModel) {
  const RigidBodyDevice dev;
  const GraspMassModel grasp(dev, 0.3, 1e-4);
  PipelineConfig base;
  base.method = Method::kPmiPd;
  base.proxy.mass = 0.02;
  base.proxy.inertia = Mat3::Identity() * 2e-6;
  base.coupling = CouplingGains{800.0, 0.3, 0.2, 1e-4};
  base.observer_gain = VecX::Constant(6, 100.0);
  base.tool = tool_preset("handpiece");
  for (const bool gripped : {true, false}) {
    PipelineConfig with = base;
    with.grasp_model = &grasp;
    with.grip_detector.start_gripped = gripped;
    with.grip_detector.release_threshold = 1e30;  // never switches
    with.grip_detector.grip_threshold = 1e30;
    ReferencePipeline detected(dev, with);
    ReferencePipeline fixed(gripped ? static_cast<const SixDofDeviceModel&>(grasp) : dev, base);
    HalfSpaceWall wall_a(Vec3::Zero(), Vec3::UnitZ(), 1e-3, 3000.0, 0.0);
    HalfSpaceWall wall_b(Vec3::Zero(), Vec3::UnitZ(), 1e-3, 3000.0, 0.0);
    Pose pose;
    pose.x = Vec3(0.0, 0.0, 1e-3);
    DeviceSample s;
    s.q = dev.joint_position(pose);
    s.qd = VecX::Zero(6);
    detected.reset(s);
    fixed.reset(s);
    double worst = 0.0, largest = 0.0;
    for (int k = 1; k <= 400; ++k) {
      const double t = 1e-3 * k;
      pose.x = Vec3(2e-3 * std::sin(7.0 * t), 1e-3 * std::cos(5.0 * t), 1e-3 - 4e-3 * t);
      pose.R = exp_so3(Vec3(0.1 * std::sin(3.0 * t), 0.05 * t, 0.0));
      const VecX q = dev.joint_position(pose);
      s.qd = (q - s.q) / 1e-3;
      s.q = q;
      s.t = t;
      const TickResult& a = detected.tick(s, 1e-3, wall_a);
      const TickResult& b = fixed.tick(s, 1e-3, wall_b);
      ASSERT_EQ(a.grip_state, gripped ? 1 : 0);
      ASSERT_EQ(b.grip_state, -1);
      worst = std::max(worst, (a.tau - b.tau).cwiseAbs().maxCoeff());
      largest = std::max(largest, b.tau.cwiseAbs().maxCoeff());
    }
    EXPECT_GT(largest, 0.5) << "the wall must load the device";
    EXPECT_LT(worst, 1e-12 * std::max(1.0, largest)) << (gripped ? "gripped" : "released");
  }
  // The detector's grasp model must be built on the pipeline's device model.
  const RigidBodyDevice other;
  const GraspMassModel foreign(other, 0.3, 1e-4);
  PipelineConfig bad = base;
  bad.grasp_model = &foreign;
  EXPECT_THROW(ReferencePipeline(dev, bad), std::invalid_argument);
}

// A bad tick never throws (it may run inside a device's servo callback): it returns a status
// naming the failure and commands exactly zero torque.
TEST(Tick, BadTickLengthOrSampleReturnsANamedStatusAndZeroTorque) {
  const RigidBodyDevice dev;
  PipelineConfig cfg;
  cfg.coupling.k_lin = 400.0;
  ReferencePipeline p(dev, cfg);
  DeviceSample s;
  s.q = dev.joint_position(Pose{Vec3(0.01, 0.0, 0.0), Mat3::Identity()});
  s.qd = VecX::Zero(6);
  ASSERT_EQ(p.reset(s), TickStatus::kOk);
  // Move the device away from the proxy so that a good tick commands a force.
  s.q(0) = 0.02;
  s.t = 1e-3;
  NoContacts none;
  EXPECT_EQ(p.tick(s, 1e-3, none).status, TickStatus::kOk);
  EXPECT_GT(p.tick(s, 1e-3, none).tau.norm(), 1.0);
  for (const double T : {0.0, -1e-3, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const TickResult& r = p.tick(s, T, none);
    EXPECT_EQ(r.status, TickStatus::kBadTickLength) << T;
    EXPECT_STREQ(tick_status_name(r.status), "tick_bad_length");
    EXPECT_EQ(r.tau.norm(), 0.0);
  }
  for (const int field : {0, 1, 2}) {
    DeviceSample bad = s;
    if (field == 0) bad.q(3) = std::nan("");
    if (field == 1) bad.qd(1) = std::numeric_limits<double>::infinity();
    if (field == 2) bad.t = std::nan("");
    const TickResult& r = p.tick(bad, 1e-3, none);
    EXPECT_EQ(r.status, TickStatus::kBadSample) << field;
    EXPECT_STREQ(tick_status_name(r.status), "tick_bad_sample");
    EXPECT_EQ(r.tau.norm(), 0.0);
  }
  DeviceSample short_sample = s;
  short_sample.q = VecX::Zero(3);
  EXPECT_EQ(p.tick(short_sample, 1e-3, none).status, TickStatus::kBadSample);
  // A good tick afterwards is computed again.
  EXPECT_EQ(p.tick(s, 1e-3, none).status, TickStatus::kOk);
  EXPECT_GT(p.tick(s, 1e-3, none).tau.norm(), 1.0);
}

// An environment whose contact set does not fit the tick's buffer, and one reporting a malformed
// contact: named statuses, zero torque, no exception.
class OverfullProvider : public ContactProvider {
 public:
  explicit OverfullProvider(bool malformed) : malformed_(malformed) {}
  bool contacts(const Pose& proxy, std::vector<Contact>& out) override {
    out.clear();
    Contact c;
    c.x_o = proxy.x;
    c.stiffness = 1000.0;
    if (malformed_) {
      c.n = Vec3(0.0, 0.0, 2.0);  // not a unit normal
      out.push_back(c);
      return true;
    }
    while (out.size() < out.capacity()) out.push_back(c);
    return false;  // more members than fit
  }

 private:
  bool malformed_;
};

TEST(Tick, FullContactBufferAndMalformedContactsAreNamedStatuses) {
  const RigidBodyDevice dev;
  ReferencePipeline p(dev, PipelineConfig{});
  DeviceSample s;
  s.q = VecX::Zero(6);
  s.qd = VecX::Zero(6);
  p.reset(s);
  OverfullProvider full(false), bad(true);
  const std::size_t capacity = p.data().r.contacts.capacity();
  EXPECT_EQ(capacity, kContactCapacity);
  const TickResult& r1 = p.tick(s, 1e-3, full);
  EXPECT_EQ(r1.status, TickStatus::kContactBufferFull);
  EXPECT_STREQ(tick_status_name(r1.status), "tick_contact_buffer_full");
  EXPECT_EQ(r1.contacts.capacity(), capacity) << "the buffer must never grow";
  EXPECT_EQ(r1.tau.norm(), 0.0);
  const TickResult& r2 = p.tick(s, 1e-3, bad);
  EXPECT_EQ(r2.status, TickStatus::kBadContact);
  EXPECT_EQ(r2.tau.norm(), 0.0);
}

// pmi-pd with friction and the handpiece's locked dynamics, for the wall-path tests below.
PipelineConfig pmi_pd_friction_config() {
  PipelineConfig cfg;
  cfg.method = Method::kPmiPd;
  cfg.observer_gain = VecX::Constant(6, 100.0);
  cfg.tool = tool_preset("handpiece");
  cfg.friction.enabled = true;
  return cfg;
}

// Step k of a path that starts 0.8 mm above the wall z = 0 (k = 0: at rest) and slides along it
// while sinking 20 um a millisecond; the velocity is the backward difference.
void wall_path_sample(const RigidBodyDevice& dev, int k, DeviceSample* s) {
  Pose pose;
  pose.x = Vec3(1e-4 * k, 0.0, 0.8e-3 - 2e-5 * k);
  const VecX q = dev.joint_position(pose);
  s->qd = k == 0 ? VecX::Zero(6) : VecX((q - s->q) / 1e-3);
  s->q = q;
  s->t = 1e-3 * k;
}

// The registry drives the tick: running the reference table's stages one by one on a copy of the
// data gives exactly what tick() gives, and the stage list is the one fast/ implements.
TEST(Tick, RegistryStagesInOrderAreTheTick) {
  const char* expected[kStageCount] = {"device_terms", "observe", "collide", "assemble",
                                       "solve",        "command", "drill"};
  for (int i = 0; i < kStageCount; ++i) EXPECT_STREQ(tick_stage_name(i), expected[i]);
  EXPECT_STREQ(reference_stage_table().implementation, "reference");

  const RigidBodyDevice dev;
  ReferencePipeline p(dev, pmi_pd_friction_config());
  DeviceSample s;
  wall_path_sample(dev, 0, &s);
  p.reset(s);
  HalfSpaceWall wall(Vec3::Zero(), Vec3::UnitZ(), 1e-3, 3000.0, 2.0);
  for (int k = 1; k <= 50; ++k) {
    wall_path_sample(dev, k, &s);
    // By hand, on a copy of the data: the stages in registry order.
    PipelineData d = p.data();
    d.q = s.q;
    d.qd = s.qd;
    d.t = s.t;
    d.T = 1e-3;
    d.env = &wall;
    for (int i = 0; i < kStageCount; ++i) {
      ASSERT_EQ(reference_stage_table().stage[i](p.model(), d), TickStatus::kOk) << i;
    }
    const TickResult& r = p.tick(s, 1e-3, wall);
    ASSERT_EQ(r.status, TickStatus::kOk);
    EXPECT_EQ((r.tau - d.r.tau).norm(), 0.0);
    EXPECT_EQ((p.proxy().pose.x - d.proxy.pose.x).norm(), 0.0);
    if (k > 10) {
      EXPECT_FALSE(r.contacts.empty()) << "the proxy must be in contact with the wall";
    }
  }
}

// Stage timing off (PipelineConfig::time_stages = false): no clock is read and stage_ns stays zero,
// while every output is bitwise the timed tick's, tick after tick (through contact, friction and
// a failed tick).
TEST(Tick, UntimedStagesLeaveTheTimesZeroAndChangeNothingElse) {
  const RigidBodyDevice dev;
  PipelineConfig cfg = pmi_pd_friction_config();
  ReferencePipeline timed(dev, cfg);
  cfg.time_stages = false;
  ReferencePipeline untimed(dev, cfg);
  EXPECT_TRUE(timed.model().time_stages);
  EXPECT_FALSE(untimed.model().time_stages);
  DeviceSample s;
  wall_path_sample(dev, 0, &s);
  timed.reset(s);
  untimed.reset(s);
  HalfSpaceWall wall(Vec3::Zero(), Vec3::UnitZ(), 1e-3, 3000.0, 2.0);
  int in_contact = 0;
  for (int k = 1; k <= 60; ++k) {
    wall_path_sample(dev, k, &s);
    const double T = k == 30 ? -1.0 : 1e-3;  // one bad tick length: a named failure in both
    const TickResult& a = timed.tick(s, T, wall);
    const TickResult& b = untimed.tick(s, T, wall);
    ASSERT_EQ(a.status, b.status) << k;
    EXPECT_EQ(a.status == TickStatus::kOk, k != 30) << k;
    for (int i = 0; i < 6; ++i) EXPECT_EQ(a.tau(i), b.tau(i)) << k;
    EXPECT_EQ((timed.proxy().pose.x - untimed.proxy().pose.x).norm(), 0.0) << k;
    EXPECT_EQ(a.contacts.size(), b.contacts.size()) << k;
    for (int i = 0; i < kStageCount; ++i) EXPECT_EQ(b.stage_ns[i], 0) << k << " " << i;
    in_contact += a.contacts.empty() ? 0 : 1;
  }
  EXPECT_GT(in_contact, 30);  // the comparison covers contact ticks, not only free space
}

}  // namespace
}  // namespace dentsim
