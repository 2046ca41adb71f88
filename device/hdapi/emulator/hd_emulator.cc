// libdentsim_hd_emulator.so: an emulator of the OpenHaptics HDAPI library (issue #15) for tests
// and for dentsim users without a device. It exports the C entry points of hdapi_abi.h with the
// documented behaviour (docs/device_facts.md §5) and runs the MuJoCo-simulated Phantom
// Premium 1.5/6DoF (device/phantom_device.h, default model file, started at rest at the middle of
// the joint ranges) behind its own 1 kHz scheduler thread.
//
// Behaviour (what a client may rely on, as with the vendor library):
// - hdInitDevice(HD_DEFAULT_DEVICE or "Default PHANToM" / "Default Device"): one device, handle 0;
//   any other name, or a second init without hdDisableDevice, fails (HD_INVALID_HANDLE, and
//   HD_DEVICE_FAULT / HD_DEVICE_ALREADY_INITIATED on the error stack).
// - Errors go on a stack; hdGetError() pops the most recent one ({HD_SUCCESS, 0, handle} when
//   empty). Errors raised in a scheduler tick are read by the callbacks that run after them.
// - The scheduler (hdStartScheduler) calls every scheduled callback once per tick, highest
//   priority first, at the rate of hdSetSchedulerRate (default 1000 Hz) on absolute deadlines;
//   late ticks are skipped, not replayed (no callback runs for them), but the simulated device's
//   physics runs through them with the torque held, as a real arm keeps moving while the
//   scheduler is late (at most 2000 periods at once). A callback returning HD_CALLBACK_DONE is
//   unscheduled.
//   hdScheduleSynchronous runs its callback in the scheduler thread (in the caller's thread when
//   the scheduler is not running) until it returns DONE, and blocks until then.
// - A frame (hdBeginFrame .. hdEndFrame) sees the state sampled at the start of the tick. Torques
//   set with hdSetDoublev(HD_CURRENT_JOINT_TORQUE / HD_CURRENT_GIMBAL_TORQUE) [mN m, vendor joint
//   convention] are committed at hdEndFrame and held (zero-order hold) over the next physics tick,
//   only while HD_FORCE_OUTPUT is enabled. A torque beyond the nominal peak raises
//   HD_EXCEEDED_MAX_FORCE and is not applied. Nested begin / unmatched end: HD_ILLEGAL_BEGIN /
//   HD_ILLEGAL_END.
// - hdGetSchedulerTimeStamp(): seconds since the start of the current scheduler tick.
// - Vendor joint convention (as the emulator reports it): the base angle is positive clockwise
//   seen from above, so vendor q1 = -q1 of dentsim (device/hdapi/hdapi_device.h); q2, q3 (absolute
//   forearm angle, includes q2) and the gimbal angles equal dentsim's. Torques map the same way.
//
// Failure injection, read at hdInitDevice from the environment (docs/hardware.md):
//   DENTSIM_HD_EMU_INIT_FAIL=CODE     hdInitDevice fails with error CODE (e.g. 0x0300; 1 = 0x0300)
//   DENTSIM_HD_EMU_COMM_ERROR_AT=N    from scheduler tick N on, every frame raises HD_COMM_ERROR
//                                     and no torque reaches the motors
//   DENTSIM_HD_EMU_STALL_AT=N         the scheduler thread stalls once at tick N ...
//   DENTSIM_HD_EMU_STALL_MS=M         ... for M ms (default 200)
//   DENTSIM_HD_EMU_WARM_AT=N          from tick N on, HD_MOTOR_TEMPERATURE reads 1.0 for every
//   motor
//                                     and every frame raises HD_WARM_MOTORS (no torque applied)
//   DENTSIM_HD_EMU_DONE_AT=N          at tick N every asynchronous callback is treated as having
//                                     returned HD_CALLBACK_DONE (it is unscheduled)
//   DENTSIM_HD_EMU_GRAVITY=0          gravity off in the simulated device (it then rests in place)
//   DENTSIM_HD_EMU_CATCH_UP=0         skipped ticks do not advance the physics (one physics period
//                                     per callback tick, for comparisons by tick index)
//   DENTSIM_HD_EMU_SCENE=NAME|FILE    the device and the scripted hand of that scene
//                                     (sim/scene_device.h: the plant `dentsim run` simulates),
//                                     the hand's clock starting at hdInitDevice; a scene that does
//                                     not load fails hdInitDevice (HD_DEVICE_FAULT, reason on
//                                     stderr)
//   DENTSIM_HD_EMU_SERIAL=S           the serial number reported (default "EMU-00001")
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "device/hdapi/hdapi_abi.h"
#include "device/phantom_device.h"
#include "sim/scene_device.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"

#define HD_EMU_EXPORT extern "C" __attribute__((visibility("default")))

namespace {

using dentsim::VecX;
namespace hd = dentsim::hd;
using Clock = std::chrono::steady_clock;

long env_long(const char* name, long fallback) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return fallback;
  return std::strtol(v, nullptr, 0);
}

struct Callback {
  HDSchedulerCallback fn;
  void* data;
  HDushort priority;
  HDSchedulerHandle handle;
  bool synchronous;
  bool done = false;
};

// Nominal limits reported (docs/device_facts.md §3: CHAI3D's figures, vendor sheet, OpenHaptics'
// clamps).
constexpr double kMaxForceN = 8.5, kMaxContinuousForceN = 1.4, kMaxStiffnessNPerMm = 3.5;
constexpr std::array<double, 3> kGimbalContinuousMnm = {188, 188, 48};
constexpr std::array<double, 6> kPeakMnm = {1720, 1440, 1440, 188, 188, 48};
constexpr long kMaxCatchUpTicks = 2000;  // skipped periods simulated at once after an overrun

class Emulator {
 public:
  std::mutex mu;                    // everything below except the atomics
  std::condition_variable cv;       // synchronous calls and hdWaitForCompletion
  std::vector<HDErrorInfo> errors;  // error stack (top = back)
  bool initialized = false;
  bool force_output = false;
  bool in_frame = false;
  long rate_hz = 1000;
  std::unique_ptr<dentsim::ScriptedHand> hand;  // DENTSIM_HD_EMU_SCENE's (outlives `device`)
  std::unique_ptr<dentsim::SimulatedPhantom> device;
  std::array<double, 6> q_frame{};   // vendor angles of the current tick [rad]
  std::array<double, 6> tau_set{};   // set in the open frame [mN m], vendor convention
  std::array<double, 6> tau_held{};  // committed at the last hdEndFrame [mN m]
  std::vector<Callback> callbacks;
  HDSchedulerHandle next_handle = 1;
  std::thread thread;
  std::atomic<bool> running{false};
  std::atomic<long> tick{0};
  Clock::time_point tick_start = Clock::now();
  std::string serial = "EMU-00001";
  // Injection.
  long init_fail = 0, comm_error_at = -1, stall_at = -1, stall_ms = 200, warm_at = -1, done_at = -1;
  bool gravity = true;
  bool catch_up = true;  // DENTSIM_HD_EMU_CATCH_UP: physics through skipped ticks
  std::string scene;

  ~Emulator() {  // a process exiting with the scheduler running
    running.store(false);
    if (thread.joinable()) thread.join();
  }

  // Per-tick storage, sized once so a scheduler tick does not allocate (tests count allocations
  // on the scheduler thread to prove the backend's callback allocation-free).
  dentsim::DeviceSample sample;
  VecX tau_device = VecX::Zero(6);
  std::vector<Callback> order;
  static constexpr std::size_t kMaxErrors = 64;     // the oldest error is dropped beyond this
  static constexpr std::size_t kMaxCallbacks = 32;  // HD_SCHEDULER_FULL beyond this

  Emulator() {
    errors.reserve(kMaxErrors);
    callbacks.reserve(kMaxCallbacks);
    order.reserve(kMaxCallbacks);
  }

  // Whether callback `h` is scheduled; removes it (and wakes waiters). Both with `mu` held.
  bool scheduled_locked(HDSchedulerHandle h) const {
    return std::any_of(callbacks.begin(), callbacks.end(),
                       [h](const Callback& c) { return c.handle == h; });
  }
  bool unschedule_locked(HDSchedulerHandle h) {
    const auto it = std::find_if(callbacks.begin(), callbacks.end(),
                                 [h](const Callback& c) { return c.handle == h; });
    if (it == callbacks.end()) return false;
    callbacks.erase(it);
    cv.notify_all();
    return true;
  }

  void push_error(HDerror code) {
    if (errors.size() == kMaxErrors) errors.erase(errors.begin());
    errors.push_back({code, static_cast<int>(code), 0});
  }

  void read_env() {
    init_fail = env_long("DENTSIM_HD_EMU_INIT_FAIL", 0);
    if (init_fail == 1) init_fail = hd::kDeviceFault;
    comm_error_at = env_long("DENTSIM_HD_EMU_COMM_ERROR_AT", -1);
    stall_at = env_long("DENTSIM_HD_EMU_STALL_AT", -1);
    stall_ms = env_long("DENTSIM_HD_EMU_STALL_MS", 200);
    warm_at = env_long("DENTSIM_HD_EMU_WARM_AT", -1);
    done_at = env_long("DENTSIM_HD_EMU_DONE_AT", -1);
    gravity = env_long("DENTSIM_HD_EMU_GRAVITY", 1) != 0;
    catch_up = env_long("DENTSIM_HD_EMU_CATCH_UP", 1) != 0;
    const char* sc = std::getenv("DENTSIM_HD_EMU_SCENE");
    scene = sc != nullptr ? sc : "";
    const char* s = std::getenv("DENTSIM_HD_EMU_SERIAL");
    serial = (s != nullptr && *s != '\0') ? s : "EMU-00001";
  }

  // Vendor convention <-> dentsim's simulated device (see the header).
  void sample_locked() {
    device->read(sample);
    for (int i = 0; i < 6; ++i) q_frame[i] = sample.q[i];
    q_frame[0] = -sample.q[0];
  }
  void advance_locked() {
    for (int i = 0; i < 6; ++i) tau_device[i] = tau_held[i] / 1000.0;
    tau_device[0] = -tau_device[0];
    device->write(tau_device);
    device->advance();
    device->clear_faults();  // the vendor device has no such latch: its command is clamped
  }
  bool warm() const { return warm_at >= 0 && tick.load() >= warm_at; }

  void run_tick(long k) {
    {
      std::lock_guard<std::mutex> lock(mu);
      tick_start = Clock::now();
      sample_locked();
    }
    if (k == stall_at) std::this_thread::sleep_for(std::chrono::milliseconds(stall_ms));
    // Callbacks, highest priority first; run without the lock (they call back into the API).
    {
      std::lock_guard<std::mutex> lock(mu);
      order.assign(callbacks.begin(), callbacks.end());  // within the reserved capacity
    }
    // Highest priority first, equal priorities in the order they were scheduled.
    std::sort(order.begin(), order.end(), [](const Callback& a, const Callback& b) {
      return a.priority != b.priority ? a.priority > b.priority : a.handle < b.handle;
    });
    for (const Callback& c : order) {
      HDCallbackCode code = c.fn(c.data);
      if (!c.synchronous && k == done_at) code = hd::kCallbackDone;
      if (code == hd::kCallbackDone) {
        std::lock_guard<std::mutex> lock(mu);
        unschedule_locked(c.handle);
      }
    }
    std::lock_guard<std::mutex> lock(mu);
    advance_locked();
  }

  void scheduler_loop() {
    const auto period = std::chrono::nanoseconds(1000000000L / rate_hz);
    auto deadline = Clock::now();
    while (running.load()) {
      run_tick(tick.load());
      tick.fetch_add(1);
      deadline += period;
      const auto now = Clock::now();
      if (deadline < now) {  // overrun: skip the missed ticks, never replay them in a burst
        const auto behind = (now - deadline) / period + 1;
        deadline += behind * period;
        // The device does not stop while the scheduler is late: its physics runs through the
        // skipped periods with the torque held (as a real arm keeps moving), so the simulated
        // time follows the clock the client measures its ticks with.
        const long steps =
            catch_up ? std::min<long>(static_cast<long>(behind), kMaxCatchUpTicks) : 0;
        for (long i = 0; i < steps && running.load(); ++i) {
          std::lock_guard<std::mutex> lock(mu);
          advance_locked();
        }
      }
      std::this_thread::sleep_until(deadline);
    }
  }
};

Emulator& emu() {
  static Emulator e;
  return e;
}

// A frame's error: HD_COMM_ERROR / HD_WARM_MOTORS injected, else force checks.
void end_frame_locked(Emulator& e) {
  const long k = e.tick.load();
  if (e.comm_error_at >= 0 && k >= e.comm_error_at) {
    e.push_error(hd::kCommError);
    e.tau_held = {};
    return;
  }
  if (e.warm()) {
    e.push_error(hd::kWarmMotors);
    e.tau_held = {};
    return;
  }
  for (int i = 0; i < 6; ++i) {
    if (std::abs(e.tau_set[i]) > kPeakMnm[i]) {
      e.push_error(hd::kExceededMaxForce);
      e.tau_held = {};
      return;
    }
  }
  e.tau_held = e.force_output ? e.tau_set : std::array<double, 6>{};
}

}  // namespace

HD_EMU_EXPORT HHD hdInitDevice(HDstring name) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  e.read_env();
  if (e.initialized) {
    e.push_error(hd::kDeviceAlreadyInitiated);
    return hd::kInvalidHandle;
  }
  if (name != nullptr && std::strcmp(name, "Default PHANToM") != 0 &&
      std::strcmp(name, "Default Device") != 0) {
    e.push_error(hd::kDeviceFault);
    return hd::kInvalidHandle;
  }
  if (e.init_fail != 0) {
    e.push_error(static_cast<HDerror>(e.init_fail));
    return hd::kInvalidHandle;
  }
  try {
    dentsim::PhantomParams p = dentsim::default_phantom_params();
    dentsim::SimulatedDeviceConfig cfg = dentsim::phantom_device_config(p);
    if (!e.scene.empty()) {
      const dentsim::Scene sc = dentsim::load_scene(e.scene);
      p = dentsim::scene_phantom_params(sc);
      cfg = dentsim::scene_device_config(sc, p);
      const dentsim::PhantomModel model(p);
      e.hand = std::make_unique<dentsim::ScriptedHand>(
          dentsim::scene_hand(sc, model.forward_kinematics(dentsim::phantom_home_q(p))));
    }
    cfg.gravity = e.gravity;
    e.device = std::make_unique<dentsim::SimulatedPhantom>(dentsim::phantom_plant(p), cfg,
                                                           dentsim::phantom_home_q(p));
    if (e.hand) e.device->set_hand(e.hand.get());
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "dentsim HD emulator: %s\n", ex.what());
    e.device.reset();
    e.hand.reset();
    e.push_error(hd::kDeviceFault);
    return hd::kInvalidHandle;
  }
  e.initialized = true;
  e.force_output = false;
  e.in_frame = false;
  e.tau_set = {};
  e.tau_held = {};
  e.tick.store(0);
  e.sample = e.device->make_sample();
  e.sample_locked();
  return 0;
}

HD_EMU_EXPORT void hdStopScheduler() {
  Emulator& e = emu();
  if (e.running.exchange(false) && e.thread.joinable()) e.thread.join();
  std::lock_guard<std::mutex> lock(e.mu);
  e.cv.notify_all();
}

HD_EMU_EXPORT void hdDisableDevice(HHD h) {
  Emulator& e = emu();
  hdStopScheduler();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.initialized || h != 0) {
    e.push_error(hd::kBadHandle);
    return;
  }
  e.callbacks.clear();
  e.device.reset();
  e.hand.reset();
  e.initialized = false;
}

HD_EMU_EXPORT void hdMakeCurrentDevice(HHD h) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.initialized || h != 0) e.push_error(hd::kBadHandle);
}

HD_EMU_EXPORT HDErrorInfo hdGetError() {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (e.errors.empty()) return {hd::kSuccess, 0, 0};
  const HDErrorInfo top = e.errors.back();
  e.errors.pop_back();
  return top;
}

HD_EMU_EXPORT HDstring hdGetErrorString(HDerror code) {
  switch (code) {
    case hd::kSuccess:
      return "No error";
    case hd::kCommError:
      return "Communication error";
    case hd::kWarmMotors:
      return "Motors are warm";
    case hd::kDeviceFault:
      return "Device fault (device not found or not initialised)";
    case hd::kExceededMaxForce:
      return "Exceeded max force";
    default:
      return "HD error";
  }
}

HD_EMU_EXPORT void hdEnable(HDenum cap) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (cap == hd::kForceOutput) {
    e.force_output = true;
  } else if (cap != hd::kMaxForceClamping && cap != hd::kForceRamping &&
             cap != hd::kSoftwareForceLimit) {
    e.push_error(hd::kInvalidEnum);
  }
}

HD_EMU_EXPORT void hdDisable(HDenum cap) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (cap == hd::kForceOutput) {
    e.force_output = false;
    e.tau_held = {};
  }
}

HD_EMU_EXPORT HDboolean hdIsEnabled(HDenum cap) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  return cap == hd::kForceOutput && e.force_output ? 1 : 0;
}

HD_EMU_EXPORT void hdBeginFrame(HHD h) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.initialized || h != 0) {
    e.push_error(hd::kBadHandle);
  } else if (e.in_frame) {
    e.push_error(hd::kIllegalBegin);
  } else {
    e.in_frame = true;
    e.tau_set = e.tau_held;  // unset torques keep their value
  }
}

HD_EMU_EXPORT void hdEndFrame(HHD h) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.initialized || h != 0) {
    e.push_error(hd::kBadHandle);
  } else if (!e.in_frame) {
    e.push_error(hd::kIllegalEnd);
  } else {
    e.in_frame = false;
    end_frame_locked(e);
  }
}

HD_EMU_EXPORT void hdGetDoublev(HDenum what, HDdouble* out) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.initialized) {
    e.push_error(hd::kInvalidOperation);
    return;
  }
  switch (what) {
    case hd::kCurrentJointAngles:
      for (int i = 0; i < 3; ++i) out[i] = e.q_frame[i];
      return;
    case hd::kCurrentGimbalAngles:
      for (int i = 0; i < 3; ++i) out[i] = e.q_frame[3 + i];
      return;
    case hd::kCurrentJointTorque:
    case hd::kLastJointTorque:
      for (int i = 0; i < 3; ++i) out[i] = e.tau_held[i];
      return;
    case hd::kCurrentGimbalTorque:
    case hd::kLastGimbalTorque:
      for (int i = 0; i < 3; ++i) out[i] = e.tau_held[3 + i];
      return;
    case hd::kMotorTemperature:
      for (int i = 0; i < 6; ++i) out[i] = e.warm() ? 1.0 : 0.2;
      return;
    case hd::kNominalMaxForce:
      *out = kMaxForceN;
      return;
    case hd::kNominalMaxContinuousForce:
      *out = kMaxContinuousForceN;
      return;
    case hd::kNominalMaxStiffness:
      *out = kMaxStiffnessNPerMm;
      return;
    case hd::kNominalMaxTorqueForce:
      for (int i = 0; i < 3; ++i) out[i] = kPeakMnm[3 + i];
      return;
    case hd::kNominalMaxTorqueContinuousForce:
      for (int i = 0; i < 3; ++i) out[i] = kGimbalContinuousMnm[i];
      return;
    default:
      e.push_error(hd::kInvalidEnum);
  }
}

HD_EMU_EXPORT void hdSetDoublev(HDenum what, const HDdouble* in) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.in_frame) {
    e.push_error(hd::kFrameError);
    return;
  }
  if (what == hd::kCurrentJointTorque) {
    for (int i = 0; i < 3; ++i) e.tau_set[i] = in[i];
  } else if (what == hd::kCurrentGimbalTorque) {
    for (int i = 0; i < 3; ++i) e.tau_set[3 + i] = in[i];
  } else {
    e.push_error(hd::kInvalidEnum);
  }
}

HD_EMU_EXPORT void hdGetIntegerv(HDenum what, HDint* out) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  switch (what) {
    case hd::kInputDof:
    case hd::kOutputDof:
      *out = 6;
      return;
    case hd::kUpdateRate:
      *out = static_cast<HDint>(e.rate_hz);
      return;
    case hd::kCurrentButtons:
      *out = 0;
      return;
    default:
      e.push_error(hd::kInvalidEnum);
  }
}

HD_EMU_EXPORT HDstring hdGetString(HDenum what) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (what == hd::kDeviceModelType) return "PHANTOM Premium 1.5 6DOF (dentsim emulator)";
  if (what == hd::kDeviceSerialNumber) return e.serial.c_str();
  e.push_error(hd::kInvalidEnum);
  return "";
}

HD_EMU_EXPORT void hdSetSchedulerRate(HDulong hz) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (hz == 0 || hz > 10000) {
    e.push_error(hd::kInvalidValue);
    return;
  }
  e.rate_hz = static_cast<long>(hz);
}

HD_EMU_EXPORT void hdStartScheduler() {
  Emulator& e = emu();
  {
    std::lock_guard<std::mutex> lock(e.mu);
    if (!e.initialized) {
      e.push_error(hd::kInvalidOperation);
      return;
    }
  }
  if (e.running.exchange(true)) return;
  e.thread = std::thread([&e] { e.scheduler_loop(); });
}

HD_EMU_EXPORT HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback cb, void* data,
                                                       HDushort priority) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (e.callbacks.size() >= Emulator::kMaxCallbacks) {
    e.push_error(hd::kSchedulerFull);
    return 0;
  }
  const HDSchedulerHandle h = e.next_handle++;
  e.callbacks.push_back({cb, data, priority, h, false});
  return h;
}

HD_EMU_EXPORT void hdScheduleSynchronous(HDSchedulerCallback cb, void* data, HDushort priority) {
  Emulator& e = emu();
  if (!e.running.load()) {
    while (cb(data) != hd::kCallbackDone) {
    }
    return;
  }
  std::unique_lock<std::mutex> lock(e.mu);
  if (e.callbacks.size() >= Emulator::kMaxCallbacks) {
    e.push_error(hd::kSchedulerFull);
    return;
  }
  const HDSchedulerHandle h = e.next_handle++;
  e.callbacks.push_back({cb, data, priority, h, true});
  e.cv.wait(lock, [&] { return !e.running.load() || !e.scheduled_locked(h); });
}

HD_EMU_EXPORT void hdUnschedule(HDSchedulerHandle h) {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  if (!e.unschedule_locked(h)) e.push_error(hd::kInvalidValue);
}

HD_EMU_EXPORT HDboolean hdWaitForCompletion(HDSchedulerHandle h, HDWaitCode code) {
  Emulator& e = emu();
  std::unique_lock<std::mutex> lock(e.mu);
  if (code == hd::kWaitCheckStatus) return e.scheduled_locked(h) ? 1 : 0;
  e.cv.wait(lock, [&] { return !e.scheduled_locked(h) || !e.running.load(); });
  return 1;
}

HD_EMU_EXPORT HDdouble hdGetSchedulerTimeStamp() {
  Emulator& e = emu();
  std::lock_guard<std::mutex> lock(e.mu);
  return std::chrono::duration<double>(Clock::now() - e.tick_start).count();
}
