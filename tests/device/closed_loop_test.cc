// The loop owner (device/closed_loop.h): the callback form of a tick equals the read/write/advance
// form tick for tick, and the safety chain's ramp-in and watchdog act through the loop as on a
// real device (the scene rig's hdapi settings: sim/simulator.cc).
#include "device/closed_loop.h"

#include <gtest/gtest.h>
#include <time.h>

#include <cstdio>
#include <memory>

#include "sim/scene.h"
#include "device/simulated_phantom.h"
#include "reference/tooth/tooth_contacts.h"
#include "sim/simulator.h"

namespace dentsim {
namespace {

std::unique_ptr<SceneRig> probe_rig() {
  SceneRigOptions o;
  o.pipeline = "fast";
  return build_scene_rig(load_scene("probe"), o);
}

// The same scene driven by ClosedLoop::step() and by step_in_callback() with the caller doing the
// device's read/write/advance (what the vendor's scheduler does around the callback): the same
// torques every tick, and the same passivity observer one tick later (the callback form accounts
// a tick when the next sample arrives).
TEST(ClosedLoop, CallbackFormEqualsTheStepFormTickForTick) {
  const auto a = probe_rig();
  const auto b = probe_rig();
  a->loop->start();
  b->loop->start();
  Device& dev_b = *b->loop_device;
  DeviceSample s = dev_b.make_sample();
  VecX tau = VecX::Zero(6);
  constexpr int kTicks = 2500;  // the probe touches the tooth after about 1 s
  int contact_ticks = 0;
  double energy_a_before_last = 0.0;
  for (int k = 0; k < kTicks; ++k) {
    energy_a_before_last = a->loop->energy_virtual_j();
    const TickResult& ra = a->loop->step();
    const VecX tau_a = a->loop->commanded_torque();
    const int contacts_a = static_cast<int>(ra.contacts.size());
    dev_b.read(s);
    const TickResult& rb = b->loop->step_in_callback(s, tau);
    ASSERT_EQ(tau, tau_a) << "tick " << k;
    ASSERT_EQ(static_cast<int>(rb.contacts.size()), contacts_a) << "tick " << k;
    dev_b.write(tau);
    dev_b.advance();
    contact_ticks += contacts_a > 0;
  }
  EXPECT_GT(contact_ticks, 500);  // the comparison covers contact
  EXPECT_FALSE(a->loop->faulted());
  EXPECT_FALSE(b->loop->faulted());
  EXPECT_EQ(b->loop->ticks(), kTicks);
  // B has accounted ticks 0 .. kTicks - 2: A's energy before its last step.
  EXPECT_NEAR(b->loop->energy_virtual_j(), energy_a_before_last,
              1e-12 + 1e-12 * std::abs(energy_a_before_last));
  EXPECT_NE(energy_a_before_last, 0.0);
}

// A pipeline that burns `burn_s` of CPU time on tick `slow_tick` (and is otherwise the rig's).
class SlowPipeline : public Pipeline {
 public:
  SlowPipeline(Pipeline& inner, long slow_tick, double burn_s)
      : inner_(inner), slow_tick_(slow_tick), burn_s_(burn_s) {}
  TickStatus reset(const DeviceSample& s) override {
    ticks_ = 0;
    return inner_.reset(s);
  }
  const TickResult& tick(const DeviceSample& s, double T, ContactProvider& c) override {
    if (ticks_++ == slow_tick_) burn();
    return inner_.tick(s, T, c);
  }
  const ProxyState& proxy() const override { return inner_.proxy(); }
  const char* name() const override { return inner_.name(); }

 private:
  void burn() const {
    auto cpu = [] {
      timespec ts{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
      return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
    };
    const double t0 = cpu();
    volatile double x = 0.0;
    while (cpu() - t0 < burn_s_) x = x + 1.0;
  }
  Pipeline& inner_;
  long slow_tick_;
  double burn_s_;
  long ticks_ = 0;
};

SafetyLimits hardware_like_limits(const SceneRig& rig) {
  SafetyLimits l;
  l.tau_max = rig.params.torque_limit_n_m;
  l.ramp_time_s = 0.5;
  l.watchdog_s = 5e-3;
  l.nominal_period = rig.tick;
  return l;
}

// A tick whose own work overruns the budget: the next tick's command is zero and the loop has
// latched `watchdog`, on the tick after the slow one; without the slow tick nothing trips.
TEST(ClosedLoop, WatchdogTripsOnATickThatOverrunsItsCpuBudget) {
  for (const bool slow : {false, true}) {
    const auto rig = probe_rig();
    SlowPipeline pipeline(*rig->pipeline, slow ? 200 : -1, 8e-3);
    ClosedLoop loop(*rig->loop_device, pipeline, *rig->contacts);
    SafetyChain chain(hardware_like_limits(*rig));
    loop.set_safety_chain(&chain);
    loop.start();
    long fault_tick = -1;
    for (long k = 0; k < 400 && fault_tick < 0; ++k) {
      loop.step();
      if (loop.faulted()) fault_tick = k;
    }
    if (!slow) {
      EXPECT_FALSE(loop.faulted()) << loop.fault_name();
      continue;
    }
    ASSERT_TRUE(loop.faulted());
    EXPECT_STREQ(loop.fault_name(), "watchdog");
    EXPECT_EQ(fault_tick, 201);  // the tick after the slow one
    EXPECT_TRUE(loop.commanded_torque().isZero(0.0));
    EXPECT_TRUE(rig->loop_device->applied_torque().isZero(0.0));
  }
}

// The field model's drilling edit falling short (no queue slot for a removed voxel; no spare
// brick likewise) is a named tick fault with zero torque, latched on the tick it happens, in both
// pipelines: the drill scene with the field model and an edit queue of one voxel, so the first
// tick that removes a voxel while one is queued overflows it (docs/derivations/field_contact.md
// §6 says why a fault and not a warning).
TEST(ClosedLoop, AFieldEditShortfallIsANamedFaultWithZeroTorque) {
  for (const char* pipeline : {"reference", "fast"}) {
    SCOPED_TRACE(pipeline);
    Scene scene = load_scene("drill");
    scene.tooth.contact_model = "field";
    SceneRigOptions o;
    o.pipeline = pipeline;
    const auto rig = build_scene_rig(scene, o);
    auto* tooth = dynamic_cast<ToothContactProvider*>(rig->contacts);
    ASSERT_NE(tooth, nullptr);
    tooth->set_field_edit_queue(1);
    ClosedLoop& loop = *rig->loop;
    loop.start();
    long fault_tick = -1, removed = 0;
    for (long k = 0; k < 10000 && !loop.faulted(); ++k) {
      ASSERT_EQ(tooth->field_edit_shortfalls(), 0) << "tick " << k;  // no fault before one
      const TickResult& r = loop.step();
      removed += r.removed_voxels;
      if (loop.faulted()) {
        fault_tick = k;
        EXPECT_EQ(r.status, TickStatus::kFieldEditShortfall);
        EXPECT_TRUE(r.tau.isZero(0.0));
      }
    }
    ASSERT_GE(fault_tick, 0) << "no shortfall in 10^4 ticks";
    std::printf("%s: fault at tick %ld after %ld voxels removed, %ld shortfalls\n", pipeline,
                fault_tick, removed, tooth->field_edit_shortfalls());
    EXPECT_GT(tooth->field_edit_shortfalls(), 0);
    EXPECT_EQ(loop.fault(), TickStatus::kFieldEditShortfall);
    EXPECT_STREQ(loop.fault_name(), "tick_field_edit_shortfall");
    EXPECT_TRUE(loop.commanded_torque().isZero(0.0));
    loop.step();  // latched: zero torque from then on
    EXPECT_STREQ(loop.fault_name(), "tick_field_edit_shortfall");
    EXPECT_TRUE(loop.commanded_torque().isZero(0.0));
  }
}

// Ramp-in: over the first 0.5 s the command is the pipeline's torque scaled by (t - t0) / 0.5
// (here below saturation and without a rate limit), then the pipeline's torque itself.
TEST(ClosedLoop, RampInScalesTheFirstHalfSecond) {
  const auto rig = probe_rig();
  ClosedLoop& loop = *rig->loop;
  SafetyChain chain(hardware_like_limits(*rig));
  loop.set_safety_chain(&chain);
  loop.start();
  const double t0 = loop.sample().t;
  double worst = 0.0;
  int checked = 0;
  for (int k = 0; k < 700; ++k) {
    const double t = loop.sample().t;
    const TickResult& r = loop.step();
    const double ramp = std::min(1.0, (t - t0) / 0.5);
    const VecX expected = ramp * r.tau;
    worst = std::max(worst, (loop.commanded_torque() - expected).cwiseAbs().maxCoeff());
    if (k == 100 || k == 600) {
      // Signal guard: the pipeline's torque (gravity compensation) is far from zero.
      ASSERT_GT(r.tau.cwiseAbs().maxCoeff(), 1e-2);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2);
  EXPECT_LT(worst, 1e-12);
  EXPECT_FALSE(loop.faulted());
}

}  // namespace
}  // namespace dentsim
