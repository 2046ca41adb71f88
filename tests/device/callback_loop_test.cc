// The loop owner inside the vendor's callback (device/callback_loop.h, issue #15): the lock-free
// record ring, and the whole drill scene ticking inside the HDAPI emulator's scheduler callback
// without a heap allocation on that thread, in contact and while drilling, every tick recorded
// in order.
#include "device/callback_loop.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <thread>

#include "device/hdapi/hdapi_device.h"
#include "sim/scene.h"
#include "sim/simulator.h"

#include "tests/support/scoped_env.h"
#include "tests/support/thread_alloc_counter.h"

using dentsim::testing::g_thread_allocs;
using dentsim::testing::t_count_thread_allocs;

namespace dentsim {
namespace {

struct Item {
  long seq = 0;
  double payload[7] = {};
};

TEST(SpscRing, HoldsItsCapacityInOrderAndRefusesWhenFull) {
  SpscRing<Item> ring(5);  // rounded up to 8
  EXPECT_EQ(ring.capacity(), 8u);
  Item it;
  EXPECT_FALSE(ring.pop(it));
  for (long i = 0; i < 8; ++i) {
    it.seq = i;
    EXPECT_TRUE(ring.push(it)) << i;
  }
  it.seq = 99;
  EXPECT_FALSE(ring.push(it));  // full: refused, nothing overwritten
  for (long i = 0; i < 8; ++i) {
    ASSERT_TRUE(ring.pop(it));
    EXPECT_EQ(it.seq, i);
  }
  EXPECT_FALSE(ring.pop(it));
}

// One producer and one consumer thread: every item arrives once, in order, intact, or was
// refused (counted) by a full ring.
TEST(SpscRing, ProducerAndConsumerThreadsLoseNothingUnaccounted) {
  SpscRing<Item> ring(64);
  constexpr long kItems = 200000;
  std::atomic<long> refused{0};
  std::atomic<bool> done{false};
  std::thread producer([&] {
    Item it;
    for (long i = 0; i < kItems; ++i) {
      it.seq = i;
      for (double& p : it.payload) p = static_cast<double>(i);
      if (!ring.push(it)) refused.fetch_add(1);
    }
    done.store(true);
  });
  long received = 0, last = -1, bad = 0;
  Item it;
  while (true) {
    if (ring.pop(it)) {
      ++received;
      if (it.seq <= last) ++bad;
      for (double p : it.payload) bad += p != static_cast<double>(it.seq);
      last = it.seq;
    } else if (done.load()) {
      if (!ring.pop(it)) break;
      ++received;
      if (it.seq <= last) ++bad;
      last = it.seq;
    }
  }
  producer.join();
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(received + refused.load(), kItems);
  EXPECT_GT(received, 0);
}

// What the servo measures of the device tip, called inside the callback: switches the counter on
// for the scheduler thread once the loop is warm (the first ticks reserve scratch buffers).
struct DepthProbe {
  SceneRig* rig = nullptr;
  std::atomic<long> calls{0};
  long warm = 300;
  std::unique_ptr<int> control;
  static double run(void* self, const Pose& pose) {
    auto& p = *static_cast<DepthProbe*>(self);
    if (p.calls.fetch_add(1) == p.warm) {
      t_count_thread_allocs = true;
      g_thread_allocs.store(0);
      p.control = std::make_unique<int>(7);  // one allocation on purpose: the counter's control
    }
    return p.rig->tip_depth(pose);
  }
};

TEST(CallbackServo, DrillSceneTicksInTheSchedulerCallbackWithoutAllocating) {
  // The emulated arm and hand advance one physics period per callback tick
  // (DENTSIM_HD_EMU_CATCH_UP=0, read at hdInitDevice): with the catch-up, a tick the loaded
  // scheduler thread delivered late let the scene's hand run on through the skipped periods
  // unobserved, and the loop met the hand's jump as a fault of its own (proxy_too_far,
  // velocity_limit, sustained_saturation at ticks 17-386 in 5 of 6 runs of the sanitizer build
  // at load 4.5, stop 51) or touched the tooth too briefly: whether the test saw contact and
  // drilling followed the machine's load. The catch-up has its own test
  // (tests/cli/hdapi_run_test.cc); this one is about allocation in the callback.
  const dentsim::testing::ScopedEnv no_catch_up("DENTSIM_HD_EMU_CATCH_UP", "0");
  const Scene scene = load_scene("drill");
  SceneRigOptions o;
  o.device = "hdapi";
  o.hd_library = DENTSIM_HD_EMULATOR;
  o.pipeline = "fast";
  const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, o);
  auto& hd = static_cast<HdapiDevice&>(*rig->backend);
  // The scheduler thread's timing is the machine's (a loaded 2-core machine under the sanitizers
  // delivered a tick 50+ ms late, tick_too_late, at tick 30): this test is about allocation in the
  // callback, so the supervisor keeps every check but the late tick's (its own tests:
  // tests/device/virtual_supervisor_test.cc). The late tick's consequence, the hand moving on
  // unobserved while the scheduler thread waits (the coupling spring stretched over that gap
  // exceeded the 34 N bound at ticks 18-57 at a load of 13-16, stop 45), is gone with the
  // catch-up: the force bounds are the scene's.
  SupervisorLimits limits = rig->supervisor->limits();
  limits.max_tick_s = -1.0;
  rig->supervisor = std::make_unique<VirtualSupervisor>(limits);
  rig->loop->set_supervisor(rig->supervisor.get());
  DepthProbe probe;
  probe.rig = rig.get();
  rig->loop->start();
  ASSERT_FALSE(rig->loop->faulted());
  long counted_ticks = 0, contact_ticks = 0, next_k = 0, out_of_order = 0;
  double energy = 0.0;
  auto removed_voxels = [&rig] {
    long n = 0;
    for (const auto v : rig->contacts->drill_state().removed_voxels) n += static_cast<long>(v);
    return n;
  };
  const long removed_before = removed_voxels();
  {
    CallbackServo servo(hd, *rig->loop, *rig->pipeline, &DepthProbe::run, &probe, 1 << 13);
    servo.start();
    TickRecord rec;
    // 3 s of the scene: the approach, then drilling from ~1.2 s on.
    while (next_k < 3000) {
      if (!servo.pop(rec)) {
        // A generous wait: a loaded machine under the sanitizers may leave the scheduler thread
        // unscheduled for longer than the device's 0.1 s tick timeout, which is not this test's
        // subject; 10 s without a tick is a stopped scheduler.
        ASSERT_TRUE(hd.wait_ticks(1, 10.0)) << "the scheduler stopped";
        continue;
      }
      out_of_order += rec.k != next_k;
      next_k = rec.k + 1;
      ASSERT_FALSE(rec.faulted) << rec.fault_name << " at tick " << rec.k;
      if (rec.k > probe.warm) {
        ++counted_ticks;
        contact_ticks += rec.contacts > 0;
      }
      energy = rec.energy_virtual_j;
    }
    servo.request_stop();
    hd.wait_ticks(2, 10.0);
    EXPECT_EQ(servo.dropped(), 0);
  }
  EXPECT_TRUE(hd.servo_done());
  const long allocations = g_thread_allocs.load();
  const long removed = removed_voxels() - removed_before;
  std::printf(
      "callback loop: %ld ticks counted, %ld in contact, %ld voxels removed, E_v %.3g J, "
      "%ld allocations on the scheduler thread (1 the control)\n",
      counted_ticks, contact_ticks, removed, energy, allocations);
  EXPECT_EQ(out_of_order, 0);
  // What the test is for: ticks in contact and drilling, inside the callback.
  EXPECT_GT(counted_ticks, 2500);
  EXPECT_GT(contact_ticks, 500);
  EXPECT_GT(removed, 100);
  ASSERT_NE(probe.control, nullptr);
  EXPECT_EQ(allocations, 1);  // the control only: the counter saw that thread, and nothing else
  EXPECT_TRUE(hd.applied_torque().isZero(0.0));  // the last callback commanded zero
}

}  // namespace
}  // namespace dentsim
