// The supervisor of the virtual side (device/virtual_supervisor.h): each invariant fires on a
// planted violation and names it, not on the value just inside its bound; through the loop owner a
// fault latches with zero torque on the very tick (device/closed_loop.h).
#include "device/virtual_supervisor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "device/closed_loop.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "reference/core/io.h"

namespace dentsim {
namespace {

// A healthy tick: proxy 1 mm from the device, 1 N of contact at 0.1 mm on 3000 N/m, at rest.
struct Healthy {
  TickResult r;
  ProxyState p;
  Healthy() {
    r.device.x = Vec3(0.1, 0.0, 0.05);
    p.pose.x = r.device.x + Vec3(0.0, 0.0, 1e-3);
    Contact c;
    c.stiffness = 3000.0;
    r.contacts.push_back(c);
    r.max_depth = 1e-4;
    r.F_contact << 0.0, 0.0, 1.0, 0.0, 0.0, 0.0;
    r.F_coupling << 0.0, 0.0, -1.0, 0.0, 0.0, 0.0;
    r.T1_vc << 0.0, 0.0, 1.0, 0.0, 0.0, 0.0;
    r.T1 = r.T1_vc;
  }
};

SupervisorFault check_once(const Healthy& h, const SupervisorLimits& l = {}) {
  VirtualSupervisor s(l);
  s.start();
  return s.check(h.r, h.p, 1e-3);
}

TEST(VirtualSupervisor, NamesEveryFault) {
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kNone), "none");
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kNonFinite), "virtual_non_finite");
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kContactForce),
               "contact_force_beyond_bound");
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kCouplingForce),
               "coupling_force_beyond_bound");
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kProxyTooDeep), "proxy_too_deep");
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kProxyTooFar), "proxy_too_far");
  EXPECT_STREQ(supervisor_fault_name(SupervisorFault::kEnergyGrowth), "virtual_energy_growth");
}

TEST(VirtualSupervisor, AHealthyTickPasses) {
  EXPECT_EQ(check_once(Healthy{}), SupervisorFault::kNone);
}

TEST(VirtualSupervisor, NonFiniteAnywhereInTheProxyOrTheCommandFires) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  {
    Healthy h;
    h.p.pose.x.x() = nan;
    EXPECT_EQ(check_once(h), SupervisorFault::kNonFinite);
  }
  {
    Healthy h;
    h.p.V(4) = inf;
    EXPECT_EQ(check_once(h), SupervisorFault::kNonFinite);
  }
  {
    Healthy h;
    h.p.pose.R(1, 2) = nan;
    EXPECT_EQ(check_once(h), SupervisorFault::kNonFinite);
  }
  {
    Healthy h;
    h.r.F_contact(2) = inf;
    EXPECT_EQ(check_once(h), SupervisorFault::kNonFinite);
  }
  {
    Healthy h;
    h.r.tau(3) = nan;
    EXPECT_EQ(check_once(h), SupervisorFault::kNonFinite);
  }
}

TEST(VirtualSupervisor, ForcesBeyondTheStatedMultipleOfThePeakForceFire) {
  const SupervisorLimits l;
  EXPECT_DOUBLE_EQ(l.force_bound_n(), 4.0 * 8.5);
  {
    Healthy h;
    h.r.F_contact(0) = 0.999 * l.force_bound_n();
    h.r.F_contact(2) = 0.0;
    EXPECT_EQ(check_once(h), SupervisorFault::kNone);
    h.r.F_contact(0) = 1.001 * l.force_bound_n();
    EXPECT_EQ(check_once(h), SupervisorFault::kContactForce);
  }
  {
    Healthy h;
    h.r.F_coupling(1) = 1.001 * l.force_bound_n();
    EXPECT_EQ(check_once(h), SupervisorFault::kCouplingForce);
  }
  {
    Healthy h;
    h.r.T1_vc(1) = -1.001 * l.force_bound_n();
    EXPECT_EQ(check_once(h), SupervisorFault::kCouplingForce);
  }
}

TEST(VirtualSupervisor, ProxyDeeperThanTheToolRadiusPlusTheBoundsCompressionFires) {
  SupervisorLimits l;
  l.tool_radius_m = 0.5e-3;
  // 3000 N/m: the force bound 34 N compresses it 11.3 mm; bound 11.8 mm.
  const double bound = 0.5e-3 + 34.0 / 3000.0;
  Healthy h;
  h.r.max_depth = 0.99 * bound;
  EXPECT_EQ(check_once(h, l), SupervisorFault::kNone);
  h.r.max_depth = 1.01 * bound;
  EXPECT_EQ(check_once(h, l), SupervisorFault::kProxyTooDeep);
  // A stiffer member in the set does not tighten the bound (the softest one's compression).
  Contact stiff;
  stiff.stiffness = 1e6;
  h.r.contacts.push_back(stiff);
  EXPECT_EQ(check_once(h, l), SupervisorFault::kProxyTooDeep);
  h.r.max_depth = 0.99 * bound;
  EXPECT_EQ(check_once(h, l), SupervisorFault::kNone);
}

TEST(VirtualSupervisor, ProxyFartherFromTheDeviceThanTheWorkspaceFires) {
  Healthy h;
  h.p.pose.x = h.r.device.x + Vec3(0.0, 0.19, 0.0);
  EXPECT_EQ(check_once(h), SupervisorFault::kNone);
  h.p.pose.x = h.r.device.x + Vec3(0.0, 0.192, 0.0);
  EXPECT_EQ(check_once(h), SupervisorFault::kProxyTooFar);
}

// The contact's work on the proxy, sum T V_hat^T F_c: a contact pushing the proxy out at 1.01 N
// and 1 m/s gives 1.01 mJ per 1 ms tick; it fires once the sum passes the tolerance (50 mJ: on
// the 50th tick, 50.5 mJ), and a contact absorbing energy (pushed into) never fires.
TEST(VirtualSupervisor, ContactGivingBackMoreThanItTookFiresPastTheTolerance) {
  Healthy h;
  h.r.V_hat << 0.0, 0.0, 1.0, 0.0, 0.0, 0.0;
  h.r.F_contact(2) = 1.01;
  VirtualSupervisor s{SupervisorLimits{}};
  s.start();
  int fired_at = -1;
  for (int k = 0; k < 100 && fired_at < 0; ++k) {
    if (s.check(h.r, h.p, 1e-3) != SupervisorFault::kNone) fired_at = k;
  }
  EXPECT_EQ(s.fault(), SupervisorFault::kEnergyGrowth);
  EXPECT_EQ(fired_at, 49);
  EXPECT_NEAR(s.value(), 0.0505, 1e-12);
  // The fault latches: a healthy tick afterwards still reports it.
  EXPECT_EQ(s.check(Healthy{}.r, Healthy{}.p, 1e-3), SupervisorFault::kEnergyGrowth);

  h.r.V_hat(2) = -1.0;  // pushed into: the contact absorbs
  s.start();
  for (int k = 0; k < 1000; ++k) ASSERT_EQ(s.check(h.r, h.p, 1e-3), SupervisorFault::kNone);
  EXPECT_NEAR(s.contact_work_j(), -1.01, 1e-9);
}

// A late tick is ridden through and counted; only one past the stated bound (default max(50 ms,
// 5 nominal periods)) is a fault.
TEST(VirtualSupervisor, LateTicksAreCountedAndOnlyOnePastTheBoundFaults) {
  SupervisorLimits l;
  l.nominal_period_s = 1e-3;
  EXPECT_DOUBLE_EQ(l.tick_bound_s(), 0.05);
  VirtualSupervisor s(l);
  s.start();
  const Healthy h;
  EXPECT_EQ(s.check(h.r, h.p, 1e-3), SupervisorFault::kNone);
  EXPECT_EQ(s.check(h.r, h.p, 1.4e-3), SupervisorFault::kNone);
  EXPECT_EQ(s.check(h.r, h.p, 5e-3), SupervisorFault::kNone);
  EXPECT_EQ(s.check(h.r, h.p, 0.049), SupervisorFault::kNone);
  EXPECT_EQ(s.late_ticks(), 2);
  EXPECT_DOUBLE_EQ(s.max_tick_s(), 0.049);
  EXPECT_EQ(s.check(h.r, h.p, 0.051), SupervisorFault::kLateTick);
  EXPECT_STREQ(supervisor_fault_name(s.fault()), "tick_too_late");
  l.nominal_period_s = 0.02;  // a 50 Hz device: 5 periods
  EXPECT_DOUBLE_EQ(l.tick_bound_s(), 0.1);
}

TEST(VirtualSupervisor, RefusesLimitsThatAreNotFinite) {
  SupervisorLimits l;
  l.peak_force_n = 0.0;
  EXPECT_THROW(VirtualSupervisor{l}, InputError);
  l = SupervisorLimits{};
  l.energy_tolerance_j = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(VirtualSupervisor{l}, InputError);
}

// A pipeline that plants a violation (a contact force of 1 kN) from tick `bad_tick` on and is
// otherwise the rig's.
class PlantingPipeline : public Pipeline {
 public:
  PlantingPipeline(Pipeline& inner, long bad_tick) : inner_(inner), bad_tick_(bad_tick) {}
  TickStatus reset(const DeviceSample& s) override {
    ticks_ = 0;
    return inner_.reset(s);
  }
  const TickResult& tick(const DeviceSample& s, double T, ContactProvider& c) override {
    out_ = inner_.tick(s, T, c);
    if (ticks_++ >= bad_tick_) out_.F_contact(0) = 1000.0;
    return out_;
  }
  const ProxyState& proxy() const override { return inner_.proxy(); }
  const char* name() const override { return inner_.name(); }

 private:
  Pipeline& inner_;
  long bad_tick_;
  long ticks_ = 0;
  TickResult out_;
};

// Through the loop owner: the violation latches contact_force_beyond_bound on the tick it appears,
// the torque of that tick and every later one is zero (while the ticks before carried gravity
// compensation), and the fault's name and time are the loop's.
TEST(VirtualSupervisor, TheLoopCommandsZeroTorqueOnTheViolatingTick) {
  SceneRigOptions o;
  o.pipeline = "fast";
  const auto rig = build_scene_rig(load_scene("probe"), o);
  ASSERT_NE(rig->supervisor, nullptr);
  PlantingPipeline planted(*rig->pipeline, 200);
  ClosedLoop loop(*rig->loop_device, planted, *rig->contacts);
  loop.set_safety_chain(rig->safety.get());
  loop.set_supervisor(rig->supervisor.get());
  loop.start();
  for (int k = 0; k < 200; ++k) {
    loop.step();
    ASSERT_FALSE(loop.faulted()) << "tick " << k << ": " << loop.fault_name();
    ASSERT_GT(loop.commanded_torque().norm(), 0.0);  // gravity compensation at least
  }
  const double t_fault = loop.sample().t;
  loop.step();
  EXPECT_TRUE(loop.faulted());
  EXPECT_EQ(loop.supervisor_fault(), SupervisorFault::kContactForce);
  EXPECT_STREQ(loop.fault_name(), "contact_force_beyond_bound");
  EXPECT_DOUBLE_EQ(loop.fault_time(), t_fault);
  EXPECT_EQ(loop.commanded_torque().norm(), 0.0);
  EXPECT_EQ(rig->loop_device->applied_torque().norm(), 0.0);
  for (int k = 0; k < 20; ++k) {
    loop.step();
    ASSERT_EQ(loop.commanded_torque().norm(), 0.0);
  }
}

}  // namespace
}  // namespace dentsim
