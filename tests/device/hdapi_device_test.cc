// The OpenHaptics backend (device/hdapi/) against the project's emulator of the vendor library
// (libdentsim_hd_emulator.so, device/hdapi/emulator/hd_emulator.cc): start-up, units and joint
// convention both ways, and every injected failure ending in its named fault with zero torque at
// the motors. The emulator runs at 1 kHz real time: each test runs a few hundred ticks at most.
#include "device/hdapi/hdapi_device.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <stdlib.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <thread>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "device/phantom_device.h"
#include "device/safety_chain.h"
#include "sim/scene_device.h"
#include "device/simulated_phantom.h"
#include "reference/phantom/phantom_model.h"

// Allocation counter for the scheduler thread (the servo test switches it on from inside the
// callback, so every allocation of that thread, the backend's tick and the emulator's, counts).
#include "tests/support/thread_alloc_counter.h"

using dentsim::testing::g_thread_allocs;
using dentsim::testing::t_count_thread_allocs;

namespace dentsim {
namespace {

// Sets the emulator's switches for one test and clears them afterwards.
class EmulatorEnv {
 public:
  EmulatorEnv(std::initializer_list<std::pair<const char*, const char*>> vars) {
    for (const auto& [name, value] : vars) {
      ::setenv(name, value, 1);
      names_.emplace_back(name);
    }
  }
  ~EmulatorEnv() {
    for (const std::string& name : names_) ::unsetenv(name.c_str());
  }

 private:
  std::vector<std::string> names_;
};

HdapiConfig emulator_config() {
  HdapiConfig c;
  c.library = DENTSIM_HD_EMULATOR;
  // Generous, so a loaded CI machine (sanitizers, parallel tests) does not read as a stalled
  // scheduler; the stall tests set their own.
  c.tick_timeout_s = 0.5;
  return c;
}

// The torque the emulator holds at its motors [mN m, vendor convention], read through the library.
std::array<double, 6> motor_torque_mnm(const HdapiDevice& dev) {
  const HdLibrary& lib = load_hd_library(dev.info().library);
  std::array<double, 6> t{};
  lib.hdGetDoublev(hd::kCurrentJointTorque, t.data());
  lib.hdGetDoublev(hd::kCurrentGimbalTorque, t.data() + 3);
  return t;
}

TEST(HdapiConvention, MapsBothWaysAndConservesPower) {
  const HdJointConvention c;
  const double qv[6] = {0.25, -0.5, 0.75, 1.0, -1.25, 1.5};
  VecX q(6), back(6);
  hd_vendor_to_dentsim_q(c, qv, q);
  EXPECT_EQ(q, (VecX(6) << -0.25, -0.5, 0.75, 1.0, -1.25, 1.5).finished());
  double qv2[6];
  hd_dentsim_to_vendor_q(c, q, qv2);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(qv2[i], qv[i]);
  // Torque: N m -> mN m, same signs as the angles, and the power tau^T qd is the same in both
  // conventions (qd maps like q).
  const VecX tau = (VecX(6) << 0.125, -0.25, 0.375, 0.0625, -0.03125, 0.015625).finished();
  double tv[6];
  hd_dentsim_to_vendor_torque(c, tau, tv);
  EXPECT_EQ(tv[0], -125.0);
  EXPECT_EQ(tv[1], -250.0);
  EXPECT_EQ(tv[5], 15.625);
  VecX tau_back(6);
  hd_vendor_to_dentsim_torque(c, tv, tau_back);
  EXPECT_EQ(tau_back, tau);
  double p_vendor = 0.0;
  for (int i = 0; i < 6; ++i) p_vendor += tv[i] * 1e-3 * qv[i];
  hd_vendor_to_dentsim_q(HdJointConvention{{-1, 1, 1, 1, 1, 1}, {}}, qv, q);
  EXPECT_DOUBLE_EQ(p_vendor, tau.dot(q));
}

TEST(HdapiLibrary, MissingLibraryListsWhereItLooked) {
  try {
    load_hd_library("/nonexistent/libHD.so");
    FAIL() << "expected HdapiError";
  } catch (const HdapiError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("tried --hd-library"), std::string::npos) << m;
    EXPECT_NE(m.find("/nonexistent/libHD.so: "), std::string::npos) << m;
  }
  // A library without the HDAPI symbols is named with the first missing one.
  try {
    load_hd_library("libm.so.6");
    FAIL() << "expected HdapiError";
  } catch (const HdapiError& e) {
    EXPECT_NE(std::string(e.what()).find("libm.so.6: opened, but does not export hdInitDevice"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(hd_library_candidates("").front(), "libHD.so");
}

TEST(HdapiDevice, StartsAndReportsTheDevice) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  EXPECT_EQ(dev.dof(), 6);
  EXPECT_EQ(dev.info().serial, "EMU-00001");
  EXPECT_EQ(dev.info().output_dof, 6);
  EXPECT_EQ(dev.info().max_force_n, 8.5);
  // Gimbal limits: the device's continuous torques (188, 188, 48) mN m.
  EXPECT_DOUBLE_EQ(dev.limits().tau_max[5], 0.048);
  EXPECT_EQ(dev.faults(), kFaultNone);
  // At rest (gravity off) at the emulator's start pose: the middle of the joint ranges, within one
  // encoder quantum.
  DeviceSample s = dev.make_sample();
  dev.read(s);
  const VecX home = (VecX(6) << 0.0, 0.35, 0.3, 0.0, 0.0, 0.0).finished();
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(s.q[i], home[i], dev.capabilities().encoder_quantum[i]);
}

TEST(HdapiDevice, TorqueReachesTheMotorsInVendorUnitsAndTurnsTheRightWay) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  DeviceSample s0 = dev.make_sample(), s = dev.make_sample();
  dev.read(s0);
  // +0.05 N m on q1 (counter-clockwise about z up in dentsim's convention).
  const VecX tau = (VecX(6) << 0.05, 0, 0, 0, 0, 0).finished();
  for (int k = 0; k < 60; ++k) {
    dev.write(tau);
    dev.advance();
  }
  dev.read(s);
  EXPECT_EQ(dev.faults(), kFaultNone) << fault_string(dev.faults());
  // At the motors: -50 mN m (the vendor's base angle turns the other way), nothing else.
  const std::array<double, 6> m = motor_torque_mnm(dev);
  EXPECT_DOUBLE_EQ(m[0], -50.0);
  for (int i = 1; i < 6; ++i) EXPECT_EQ(m[i], 0.0);
  // The base turned in +q1 (dentsim) and the vendor reports the opposite sign.
  EXPECT_GT(s.q[0] - s0.q[0], 10 * dev.capabilities().encoder_quantum[0]);
  const HdLibrary& lib = load_hd_library(dev.info().library);
  double qv[3] = {};
  lib.hdGetDoublev(hd::kCurrentJointAngles, qv);
  EXPECT_LT(qv[0], 0.0);
  EXPECT_GT(s.qd[0], 0.0);
  EXPECT_GT(s.t, s0.t);
}

// Runs the plain loop with a small torque until `fault` shows or `ticks` pass; then checks zero
// torque at the motors within one tick.
void expect_fault_and_zero_torque(HdapiDevice& dev, std::uint32_t fault, const char* name,
                                  int ticks) {
  // Small arm torques only (the gimbal links are light: a few mN m spin them up in 40 ms).
  const VecX tau = (VecX(6) << 0.01, 0.01, 0.01, 0.0, 0.0, 0.0).finished();
  int k = 0;
  for (; k < ticks && (dev.faults() & fault) == 0; ++k) {
    dev.write(tau);
    dev.advance();
  }
  ASSERT_NE(dev.faults() & fault, 0u) << "after " << k << " ticks: " << fault_string(dev.faults());
  EXPECT_NE(fault_string(dev.faults()).find(name), std::string::npos);
  dev.write(tau);  // still commanded: the latch must hold
  // One tick after the fault was seen (after a stall: the first tick once the scheduler resumes).
  bool ticked = false;
  for (int i = 0; i < 40 && !ticked; ++i) ticked = dev.wait_ticks(1);
  ASSERT_TRUE(ticked);
  EXPECT_EQ(dev.applied_torque(), VecX::Zero(6));
  const std::array<double, 6> m = motor_torque_mnm(dev);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(m[i], 0.0) << "motor " << i;
}

TEST(HdapiDevice, InitFailureNamesTheCodeAndTheCauses) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_INIT_FAIL", "0x0300"}});
  try {
    HdapiDevice dev(emulator_config());
    FAIL() << "expected HdapiError";
  } catch (const HdapiError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("hdInitDevice"), std::string::npos) << m;
    EXPECT_NE(m.find("hd_device_fault (0x0300)"), std::string::npos) << m;
    EXPECT_NE(m.find("not connected"), std::string::npos) << m;
  }
  // The library is left usable: a later start-up works.
  ::unsetenv("DENTSIM_HD_EMU_INIT_FAIL");
  HdapiDevice dev(emulator_config());
  EXPECT_EQ(dev.faults(), kFaultNone);
}

TEST(HdapiDevice, CommErrorMidRunIsHdCommError) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_COMM_ERROR_AT", "40"}, {"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  expect_fault_and_zero_torque(dev, kFaultHdCommError, "hd_comm_error", 300);
}

TEST(HdapiDevice, WarmMotorsAreHdWarmMotorsAndTheSafetyChainSeesTheTemperature) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_WARM_AT", "40"}, {"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  ASSERT_TRUE(dev.info().reports_motor_temperature);
  expect_fault_and_zero_torque(dev, kFaultHdWarmMotors, "hd_warm_motors", 300);
  const std::array<double, 6> temp = dev.motor_temperature();
  SafetyChain chain(phantom_safety_limits(VecX::Constant(6, -3.0), VecX::Constant(6, 3.0)));
  DeviceSample s = dev.make_sample();
  dev.read(s);
  chain.start(s.t);
  VecX out = VecX::Ones(6);
  EXPECT_EQ(chain.apply(s, VecX::Zero(6), 0.0, temp.data(), out), kFaultMotorTemperature);
  EXPECT_EQ(out, VecX::Zero(6));
}

TEST(HdapiDevice, SchedulerStallIsSchedulerStopped) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_STALL_AT", "40"},
                         {"DENTSIM_HD_EMU_STALL_MS", "500"},
                         {"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiConfig c = emulator_config();
  c.tick_timeout_s = 0.05;
  HdapiDevice dev(c);
  expect_fault_and_zero_torque(dev, kFaultSchedulerStopped, "scheduler_stopped", 300);
}

// Start-up waits for the scheduler's first callback by its own timeout, not a tick's: a
// scheduler whose first tick comes 300 ms late (a busy machine starting the vendor's thread)
// starts under the default 2 s, even with a tick timeout of 50 ms; a start timeout below the
// delay fails with a message naming the wait and the library.
TEST(HdapiDevice, LateFirstCallbackStartsWithinTheStartTimeoutOnly) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_STALL_AT", "0"},
                         {"DENTSIM_HD_EMU_STALL_MS", "300"},
                         {"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiConfig c = emulator_config();
  c.tick_timeout_s = 0.05;
  {
    HdapiDevice dev(c);
    EXPECT_EQ(dev.faults(), kFaultNone);
    EXPECT_GE(dev.ticks(), 1);
  }
  c.start_timeout_s = 0.1;
  try {
    HdapiDevice dev(c);
    ADD_FAILURE() << "started although the first callback came after the start timeout";
  } catch (const HdapiError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("did not call the servo callback within 0.100000 s"), std::string::npos)
        << what;
    EXPECT_NE(what.find(DENTSIM_HD_EMULATOR), std::string::npos) << what;
  }
}

TEST(HdapiDevice, CallbackEndedByTheLibraryIsSchedulerStopped) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_DONE_AT", "40"}, {"DENTSIM_HD_EMU_GRAVITY", "0"}});
  // The emulator config's generous tick timeout: a shorter one timed out before tick 40 on a
  // loaded machine (4 ticks seen), which is not what this test is about.
  HdapiConfig c = emulator_config();
  HdapiDevice dev(c);
  const VecX tau = (VecX(6) << 0.01, 0.01, 0.01, 0.0, 0.0, 0.0).finished();
  for (int k = 0; k < 300 && dev.faults() == kFaultNone; ++k) {
    dev.write(tau);
    dev.advance();
  }
  EXPECT_EQ(fault_string(dev.faults()), "scheduler_stopped");
  // Nobody commands the motors any more: without more, the emulator would hold the last frame's
  // torque (10 mN m per joint) for as long as the scheduler runs. The backend disabled force
  // output when its wait timed out: the motors hold nothing, and the library says so.
  EXPECT_GE(dev.ticks(), 40);
  EXPECT_LE(dev.ticks(), 42);
  const std::array<double, 6> held = motor_torque_mnm(dev);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(held[i], 0.0) << "joint " << i + 1;
  EXPECT_EQ(load_hd_library(dev.info().library).hdIsEnabled(hd::kForceOutput), 0);
  EXPECT_TRUE(dev.applied_torque().isZero(0.0));
}

// The servo function runs inside the vendor's callback; returning false ends the loop.
struct CountingServo {
  int calls = 0;
  double t_first = -1.0, t_last = -1.0;
  static bool run(void* self, const DeviceSample& s, VecX& tau) {
    auto* c = static_cast<CountingServo*>(self);
    if (c->t_first < 0.0) c->t_first = s.t;
    c->t_last = s.t;
    tau.setConstant(0.0);
    tau[1] = 0.02;
    return ++c->calls < 100;
  }
};

TEST(HdapiDevice, ServoFunctionRunsInTheSchedulerCallback) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  CountingServo servo;
  dev.set_servo_function(&CountingServo::run, &servo);
  for (int i = 0; i < 200 && !dev.servo_done(); ++i) dev.wait_ticks(1);
  ASSERT_TRUE(dev.servo_done());
  EXPECT_EQ(servo.calls, 100);
  EXPECT_GT(servo.t_last, servo.t_first);
  EXPECT_EQ(dev.faults(), kFaultNone);
  // The last frame (the one returning DONE) commanded zero.
  EXPECT_EQ(motor_torque_mnm(dev)[1], 0.0);
}

// The scheduler thread's policy as the servo function sees it from inside the callback. It first
// moves its own thread (the scheduler's) to `set_policy`, which an unprivileged process may pick
// (SCHED_BATCH, SCHED_OTHER), so that the scheduler's thread and the test's differ.
struct PolicyServo {
  std::atomic<int> set_policy{SCHED_BATCH};
  std::atomic<int> policy{-1}, priority{-1};
  static bool run(void* self, const DeviceSample&, VecX& tau) {
    auto* p = static_cast<PolicyServo*>(self);
    sched_param param{};
    pthread_setschedparam(pthread_self(), p->set_policy.load(), &param);
    int policy = 0;
    if (pthread_getschedparam(pthread_self(), &policy, &param) == 0) {
      p->priority.store(param.sched_priority);
      p->policy.store(policy);
    }
    tau.setZero();
    return true;
  }
};

// scheduler_policy() reads the vendor's scheduler thread, the one the tick runs on (what the
// field edit's worker is placed below with --hd-loop callback), not the caller's.
TEST(HdapiDevice, SchedulerPolicyIsTheCallbacksThreads) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  int policy = -1, priority = -1;
  PolicyServo servo;
  dev.set_servo_function(&PolicyServo::run, &servo);
  for (int i = 0; i < 200 && servo.policy.load() != SCHED_BATCH; ++i) dev.wait_ticks(1);
  ASSERT_EQ(servo.policy.load(), SCHED_BATCH) << "the scheduler's thread could not take SCHED_BATCH";
  ASSERT_TRUE(dev.scheduler_policy(&policy, &priority));
  EXPECT_EQ(policy, SCHED_BATCH);
  EXPECT_EQ(priority, servo.priority.load());
  sched_param own{};
  int own_policy = -1;
  ASSERT_EQ(pthread_getschedparam(pthread_self(), &own_policy, &own), 0);
  EXPECT_NE(own_policy, SCHED_BATCH);  // the test's thread is not the one asked
  // Back to SCHED_OTHER (the emulator's scheduler thread may outlive this device).
  servo.set_policy.store(SCHED_OTHER);
  for (int i = 0; i < 200 && servo.policy.load() != SCHED_OTHER; ++i) dev.wait_ticks(1);
  ASSERT_TRUE(dev.scheduler_policy(&policy, &priority));
  EXPECT_EQ(policy, SCHED_OTHER);
  dev.set_servo_function(nullptr, nullptr);
}

// A servo function that stays inside each call for a while, marking when it is inside.
struct SlowServo {
  std::atomic<bool> inside{false};
  std::atomic<int> calls{0};
  static bool run(void* self, const DeviceSample&, VecX& tau) {
    auto* p = static_cast<SlowServo*>(self);
    p->inside.store(true);
    p->calls.fetch_add(1);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    tau.setZero();
    p->inside.store(false);
    return true;
  }
};

// Detaching (set_servo_function(nullptr)) from another thread returns only once no callback is
// inside the old function: the caller may then destroy the servo and what it uses (a servo loop
// whose test failed early destroyed its pipeline under a running callback, found by ASan).
TEST(HdapiDevice, DetachingWaitsForTheCallbackInFlight) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  auto servo = std::make_unique<SlowServo>();
  dev.set_servo_function(&SlowServo::run, servo.get());
  int detached_inside = 0;
  for (int round = 0; round < 5; ++round) {
    // Wait until a call is in flight, then detach from this thread.
    for (int i = 0; i < 2000 && !servo->inside.load(); ++i) {
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    ASSERT_TRUE(servo->inside.load()) << "no callback entered the servo function";
    dev.set_servo_function(nullptr, nullptr);
    detached_inside += servo->inside.load() ? 1 : 0;
    const int calls = servo->calls.load();
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    EXPECT_EQ(servo->calls.load(), calls) << "a callback entered after the detach returned";
    dev.set_servo_function(&SlowServo::run, servo.get());
  }
  dev.set_servo_function(nullptr, nullptr);
  EXPECT_EQ(detached_inside, 0);
  servo.reset();  // nothing may call it now (ASan names a use after free otherwise)
  dev.wait_ticks(2, 10.0);
}

// Switches allocation counting on for the scheduler thread from inside its callback.
// Its first call allocates once, on purpose: the control that the counter sees that thread.
struct AllocationProbe {
  std::atomic<int> calls{0};
  std::unique_ptr<int> control;
  static bool run(void* self, const DeviceSample&, VecX& tau) {
    auto* p = static_cast<AllocationProbe*>(self);
    t_count_thread_allocs = true;
    if (p->calls.load() == 0) p->control = std::make_unique<int>(7);
    tau.setZero();
    p->calls.fetch_add(1);
    return true;
  }
};

TEST(HdapiDevice, SchedulerTicksDoNotAllocate) {
  const EmulatorEnv env({{"DENTSIM_HD_EMU_GRAVITY", "0"}});
  HdapiDevice dev(emulator_config());
  AllocationProbe probe;
  dev.set_servo_function(&AllocationProbe::run, &probe);
  for (int i = 0; i < 100 && probe.calls.load() < 2; ++i) dev.wait_ticks(1);
  ASSERT_GE(probe.calls.load(), 2);
  EXPECT_GE(g_thread_allocs.load(), 1);  // the control
  g_thread_allocs = 0;
  // 100 ticks through the servo function ...
  const int first = probe.calls.load();
  for (int i = 0; i < 1000 && probe.calls.load() < first + 100; ++i) dev.wait_ticks(1);
  EXPECT_GE(probe.calls.load(), first + 100);
  // ... and 100 through write() / advance() (this thread does not count).
  dev.set_servo_function(nullptr, nullptr);
  const VecX tau = (VecX(6) << 0.01, 0.01, 0.01, 0, 0, 0).finished();
  for (int k = 0; k < 100; ++k) {
    dev.write(tau);
    dev.advance();
  }
  EXPECT_EQ(dev.faults(), kFaultNone);
  EXPECT_EQ(g_thread_allocs.load(), 0);
}

// Records (tick index, q) from inside the scheduler callback into preallocated storage.
struct TrajectoryRecorder {
  static constexpr int kMax = 200;
  const HdapiDevice* dev = nullptr;
  std::array<long, kMax> tick{};
  std::array<Vec6, kMax> q{};
  std::atomic<int> n{0};
  static bool run(void* self, const DeviceSample& s, VecX& tau) {
    auto* r = static_cast<TrajectoryRecorder*>(self);
    tau.setZero();
    const int i = r->n.load();
    if (i >= kMax) return false;
    r->tick[i] = r->dev->ticks();  // this callback's index on the emulator's clock
    r->q[i] = s.q;
    r->n.store(i + 1);
    return true;
  }
};

TEST(HdapiDevice, EmulatedSceneIsTheSimulatedDeviceOfThatScene) {
  // The drill scene's device and hand behind the HDAPI, zero torque: every sample the backend
  // reads equals, bit for bit, the direct SimulatedPhantom of the scene after as many ticks
  // (one physics period per callback tick: no catch-up through ticks a loaded machine skips).
  const EmulatorEnv env({{"DENTSIM_HD_EMU_SCENE", "drill"}, {"DENTSIM_HD_EMU_CATCH_UP", "0"}});
  HdapiDevice dev(emulator_config());
  TrajectoryRecorder rec;
  rec.dev = &dev;
  dev.set_servo_function(&TrajectoryRecorder::run, &rec);
  for (int i = 0; i < 2000 && !dev.servo_done(); ++i) dev.wait_ticks(1);
  ASSERT_TRUE(dev.servo_done());

  const Scene scene = load_scene("drill");
  const PhantomParams p = scene_phantom_params(scene);
  SimulatedPhantom direct(phantom_plant(p), scene_device_config(scene, p), phantom_home_q(p));
  const ScriptedHand hand =
      scene_hand(scene, PhantomModel(p).forward_kinematics(phantom_home_q(p)));
  direct.set_hand(&hand);
  DeviceSample s = direct.make_sample();
  const VecX zero = VecX::Zero(6);
  long k = 0;
  double moved = 0.0;
  for (int i = 0; i < TrajectoryRecorder::kMax; ++i) {
    for (; k < rec.tick[i]; ++k) {
      direct.write(zero);
      direct.advance();
    }
    direct.read(s);
    ASSERT_EQ(VecX(rec.q[i]), s.q) << "emulator tick " << k;
    moved = std::max(moved, (s.q - rec.q[0]).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(moved, 1e-3);  // the hand moved the device: the comparison is not of a device at rest
}

}  // namespace
}  // namespace dentsim
