// `dentsim run SCENE --device hdapi --hd-library <emulator>` (issue #15): the whole simulator
// through the real OpenHaptics backend code (device/hdapi/hdapi_device.h) against the project's
// emulator of the vendor library, compared with the direct simulated run, and an HD error from
// the device ending the run in its named fault with zero torque and the data written.
//
// By default (--hd-loop callback) the tick runs inside the vendor's scheduler callback, once per
// scheduler tick (device/callback_loop.h): the run is compared with the direct run at the same
// 1 kHz. With --hd-loop caller the backend drives the loop through read/write/advance from the
// calling thread: a step waits until the scheduler has applied its command (tick k) and
// published the sample after it (tick k+1), so the loop runs at half the scheduler's rate, and
// the direct run it is compared with runs at 500 Hz. What differs between the two and bounds
// their agreement: the real-time scheduler's timing (T_k measured, jitter), the emulator's hand
// clock starting at hdInitDevice (a few ms before the loop's first tick), and the backend's own
// velocity estimate. The rendered stiffness (force against penetration) is what the backend must
// preserve: within 20 %. When the tool arrives and how long it stays depend on the loop's
// real-time rate (in caller form a loaded machine steps less often against the emulator's
// real-time hand): the other bounds are per form, below (docs/hardware.md). A wrong joint
// convention or torque unit misses the tooth or faults, far outside these. The test runs alone
// (RUN_SERIAL, tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/cli.h"
#include "tests/support/scoped_env.h"

namespace {

namespace fs = std::filesystem;

fs::path fresh(const std::string& name) {
  return dentsim::testing::fresh_temp_dir("dentsim_hdapi_run_" + name);
}

nlohmann::json report(const fs::path& dir) {
  return dentsim::testing::read_json_file(dir / "report.json");
}

double rel(const nlohmann::json& a, const nlohmann::json& b) {
  return std::abs(a.get<double>() - b.get<double>()) / std::abs(b.get<double>());
}

const std::string kEmulator = std::string(" --device hdapi --hd-library ") + DENTSIM_HD_EMULATOR;

// The emulator run (`extra` options) against the direct run at `direct_hz`; `*emulated` gets the
// emulator run's report. A bound of 0 leaves that figure uncompared (it depends on when the
// loop's ticks fall against the emulator's real-time hand, i.e. on the machine's load); the
// emulator run must then still have touched the tooth (max force > 0.5 N, contact ticks > 0).
struct Bounds {
  double stiffness, force, penetration, contact_ticks;  // relative
};

void expect_matches_direct(const std::string& extra, const std::string& direct_hz,
                           const std::string& hd_loop, const Bounds& bound,
                           nlohmann::json* emulated, fs::path* emulated_dir = nullptr) {
  const fs::path a = fresh("emulator_" + hd_loop), b = fresh("direct_" + direct_hz);
  if (emulated_dir != nullptr) *emulated_dir = a;
  const auto ra = dentsim::testing::run_dentsim("run probe --duration 2" + kEmulator + extra +
                                                " --out " + a.string());
  ASSERT_EQ(ra.status, 0) << ra.output;
  const auto rb = dentsim::testing::run_dentsim("run probe --duration 2 --tick-hz " + direct_hz +
                                                " --out " + b.string());
  ASSERT_EQ(rb.status, 0) << rb.output;
  const nlohmann::json e = report(a), d = report(b);
  *emulated = e;
  EXPECT_EQ(e["device"], "hdapi");
  EXPECT_EQ(e["hd_loop"], hd_loop);
  EXPECT_EQ(d["device"], "simulated-phantom");
  EXPECT_FALSE(d.contains("hd_loop"));
  EXPECT_TRUE(e["faults"].empty()) << e["faults"];
  // No ground truth on a device: the hand's work and the passivity at the hand are unknown.
  EXPECT_TRUE(e["passive_at_hand"].is_null());
  EXPECT_TRUE(e["hand_work_j"].is_null());
  // The device's clock covered the duration.
  EXPECT_NEAR(e["simulated_s"].get<double>(), 2.0, 0.01);
  ASSERT_GT(d["max_contact_force_n"].get<double>(), 0.5);  // signal guard: a real contact
  EXPECT_LT(rel(e["rendered_stiffness_n_per_m"], d["rendered_stiffness_n_per_m"]), bound.stiffness);
  if (bound.force > 0.0) {
    EXPECT_LT(rel(e["max_contact_force_n"], d["max_contact_force_n"]), bound.force);
  }
  if (bound.penetration > 0.0) {
    EXPECT_LT(rel(e["max_penetration_m"], d["max_penetration_m"]), bound.penetration);
  }
  if (bound.contact_ticks > 0.0) {
    EXPECT_LT(rel(e["contact_ticks"], d["contact_ticks"]), bound.contact_ticks);
  }
  EXPECT_GT(e["max_contact_force_n"].get<double>(), 0.5);  // the emulator run touched the tooth
  EXPECT_GT(e["contact_ticks"].get<long>(), 0);
  std::printf(
      "emulator (%s) vs direct at %s Hz: ticks %ld / %ld, max force %.3f / %.3f N, stiffness "
      "%.0f / %.0f N/m, contact ticks %ld / %ld\n",
      hd_loop.c_str(), direct_hz.c_str(), e["ticks"].get<long>(), d["ticks"].get<long>(),
      e["max_contact_force_n"].get<double>(), d["max_contact_force_n"].get<double>(),
      e["rendered_stiffness_n_per_m"].get<double>(), d["rendered_stiffness_n_per_m"].get<double>(),
      e["contact_ticks"].get<long>(), d["contact_ticks"].get<long>());
}

// The tick in the vendor's callback: one loop tick per scheduler tick (about 2000 in 2 s; a
// record dropped by a full ring would be missing from the measurements). The loop's rate no
// longer depends on the calling thread's scheduling, so the bounds on when the tool arrives are
// tighter than the caller form's. The backend's safety chain ramps force in over the first 0.5 s
// (the direct simulated run does not), so the arm starts lower and the tool arrives a little
// differently: measured over 7 runs, stiffness 1-5 %, max force 0-11 %, contact ticks 5-18 %
// (24 % with three busy processes beside it). On a loaded machine the scheduler skips ticks (1707
// of 2000 once, issue #32): the loop rides through them — each skipped tick lengthens the
// measured T_k the pipeline integrates over, counted in `late_ticks` (T_k > 1.5 periods) — and
// only a tick past the supervisor's bound (max(5 periods, 2/L) = 67 ms here: the observer's
// L T_k < 2) is a fault (under load average ~18 the emulator's scheduler once left 51 ms). What holds
// whatever the load: the device's clock covers the duration (expect_matches_direct), no record
// is dropped, at most one tick per scheduler tick, and every tick the scheduler skipped shows as
// a late tick, none beyond the bound.
// The first and the last row's time of a run's timeseries.csv (t_s: the device clock from the
// run's start, one row a tick).
std::pair<double, double> first_and_last_time(const fs::path& csv) {
  std::ifstream f(csv);
  std::string line;
  std::getline(f, line);  // the header
  double first = -1.0, last = -1.0;
  while (std::getline(f, line)) {
    if (line.empty()) continue;
    const double t = std::stod(line.substr(0, line.find(',')));
    if (first < 0.0) first = t;
    last = t;
  }
  return {first, last};
}

TEST(HdapiRun, EmulatorRunMatchesTheDirectRunAtItsRate) {
  nlohmann::json e;
  fs::path dir;
  // contact_ticks is not compared: a count of ticks against the real-time hand, it drops with
  // every tick a loaded scheduler skips (the time in contact does not).
  expect_matches_direct("", "1000", "callback", {0.20, 0.30, 0.35, 0.0}, &e, &dir);
  EXPECT_EQ(e["callback_dropped_ticks"].get<long>(), 0);
  const long ticks = e["ticks"].get<long>();
  EXPECT_GT(ticks, 0);
  EXPECT_LE(ticks, 2001);
  const long late = e["late_ticks"].get<long>();
  const double longest = e["max_tick_s"].get<double>();
  std::printf("ticks %ld, late ticks %ld, longest tick %.2f ms\n", ticks, late, longest * 1e3);
  // A tick the scheduler skipped between the first tick and the last shows as a late one. The
  // time before the first callback is no tick of the loop's (a loaded machine started it 15 ms
  // after the run's start once, stop 51: 1 985 ticks, none late), so the ticks are counted
  // against the periods from the first tick to the last on the device clock.
  const auto [t_first, t_last] = first_and_last_time(dir / "timeseries.csv");
  ASSERT_GE(t_first, 0.0) << "no row in " << (dir / "timeseries.csv");
  const long spanned = std::lround((t_last - t_first) / 1e-3) + 1;
  std::printf("first tick at %.4f s, last at %.4f s: %ld periods\n", t_first, t_last, spanned);
  if (ticks < spanned) {
    EXPECT_GT(late, 0) << "ticks were skipped without a late tick";
  }
  EXPECT_LT(longest, 2.0 / 30.0);
  EXPECT_GE(longest, 0.5e-3);  // the device clock advanced by about a period per tick
}

// The drill scene (contact, drilling through enamel into dentin) with the tick in the vendor's
// callback against the direct run at 1 kHz. Measured over 7 runs (with the backend's 0.5 s
// ramp-in): rendered stiffness 1-4 %, RMS contact force 0.5-5 %, removed volume 0-15 % (the cut
// integrates the contact's timing). Under load (a sanitizer build and a sweep beside it) it was
// 34-44 % until the emulator's physics ran through the scheduler's skipped ticks (the loop's
// measured T_k, and so the cut per tick, had grown while the simulated arm had not moved): since
// then 2.5-5.5 % under the same load.
TEST(HdapiRun, DrillSceneInTheCallbackMatchesTheDirectRun) {
  const fs::path a = fresh("drill_callback"), b = fresh("drill_direct");
  const auto ra = dentsim::testing::run_dentsim("run drill" + kEmulator + " --out " + a.string());
  ASSERT_EQ(ra.status, 0) << ra.output;
  const auto rb = dentsim::testing::run_dentsim("run drill --out " + b.string());
  ASSERT_EQ(rb.status, 0) << rb.output;
  const nlohmann::json e = report(a), d = report(b);
  EXPECT_EQ(e["hd_loop"], "callback");
  EXPECT_EQ(e["callback_dropped_ticks"].get<long>(), 0);
  EXPECT_TRUE(e["faults"].empty()) << e["faults"];
  const double removed = d["removed_volume_mm3"]["total"].get<double>();
  ASSERT_GT(removed, 1.0);  // signal guard: the direct run drilled
  ASSERT_GT(d["removed_volume_mm3"]["dentin"].get<double>(), 0.0);
  EXPECT_LT(rel(e["rendered_stiffness_n_per_m"], d["rendered_stiffness_n_per_m"]), 0.20);
  EXPECT_LT(rel(e["rms_contact_force_n"], d["rms_contact_force_n"]), 0.20);
  // (contact_ticks is not compared: a tick count, it drops with the ticks a loaded scheduler skips.)
  EXPECT_GT(e["contact_ticks"].get<long>(), 0);
  EXPECT_LT(rel(e["removed_volume_mm3"]["total"], d["removed_volume_mm3"]["total"]), 0.30);
  std::printf(
      "drill, emulator (callback) vs direct: removed %.3f / %.3f mm^3, stiffness %.0f / %.0f "
      "N/m, rms force %.3f / %.3f N\n",
      e["removed_volume_mm3"]["total"].get<double>(), removed,
      e["rendered_stiffness_n_per_m"].get<double>(), d["rendered_stiffness_n_per_m"].get<double>(),
      e["rms_contact_force_n"].get<double>(), d["rms_contact_force_n"].get<double>());
}

// The caller's loop steps when its thread is scheduled: on an idle machine every two scheduler
// ticks, on a loaded one every two to several (issue #32: it failed under load). Measured over 10
// idle runs against the direct run at 500 Hz: stiffness 1-6 % (28 % once, right after a full
// build, with a sweep beside it), max force 1-37 %, contact ticks 4-40 %: when the tool arrives
// and how long it stays follow the thread's scheduling against the emulator's real-time hand, so
// the force, penetration and contact ticks are not compared. What holds whatever the load, and
// what it catches (a wrong joint sign or torque unit: faults, no contact, or a stiffness off by
// orders of magnitude): the run ends without a fault over the device's 2 s (expect_matches_direct),
// touches the tooth, renders the direct run's stiffness within a factor of 2, steps at most once
// per two scheduler ticks, rides through every longer tick (each shows in max_tick_s, none beyond
// the supervisor's bound of 67 ms, which would have been a tick_too_late fault) and integrates
// over the measured T_k: the ticks' lengths add up to the device's clock, so fewer ticks mean
// longer ones, never lost time.
TEST(HdapiRun, CallerLoopMatchesTheDirectRunAtHalfTheRate) {
  nlohmann::json e;
  expect_matches_direct(" --hd-loop caller", "500", "caller", {0.50, 0.0, 0.0, 0.0}, &e);
  const long ticks = e["ticks"].get<long>();
  EXPECT_GT(ticks, 0);
  EXPECT_LT(ticks, 1100);  // at most one loop tick per two scheduler ticks
  const double longest = e["max_tick_s"].get<double>();
  EXPECT_GE(longest, 2e-3 - 1e-4);  // a caller tick spans at least two scheduler ticks
  EXPECT_LT(longest, 2.0 / 30.0);   // ridden through: within the supervisor's bound
  // The mean tick is the device's clock over the ticks: >= 2 ms, and the longest is at least it.
  EXPECT_GE(longest * static_cast<double>(ticks), e["simulated_s"].get<double>() - 0.01);
  std::printf("caller loop: %ld ticks, %ld late (T_k > 1.5 ms), longest tick %.2f ms\n", ticks,
              e["late_ticks"].get<long>(), longest * 1e3);
}

// What wraps or paces the caller's thread cannot run with the tick in the vendor's callback: a
// clear error before the device is touched, naming the way out.
TEST(HdapiRun, CallbackLoopRefusesWhatNeedsTheCallersLoop) {
  const fs::path a = fresh("refused");
  const auto r = dentsim::testing::run_dentsim("run probe --duration 0.5" + kEmulator +
                                               " --inject-fault frozen@0.2 --out " + a.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--inject-fault wraps the caller's loop: add --hd-loop caller"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(a / "report.json"));
}

// One of the emulator's failure switches from scheduler tick 400 on (with `extra` variables set
// as well); the run must end in `name` with zero torque over the faulting tick and the report and
// time series written.
void expect_named_stop(const char* variable, const std::string& name,
                       const std::vector<std::pair<const char*, const char*>>& extra = {}) {
  const fs::path a = fresh(name + "_" + variable);
  ::setenv(variable, "400", 1);
  for (const auto& [k, v] : extra) ::setenv(k, v, 1);
  const auto r =
      dentsim::testing::run_dentsim("run probe --duration 2" + kEmulator + " --out " + a.string());
  ::unsetenv(variable);
  for (const auto& [k, v] : extra) ::unsetenv(k);
  EXPECT_EQ(r.status, 1) << r.output;
  const nlohmann::json e = report(a);
  ASSERT_EQ(e["faults"].size(), 1u) << e;
  EXPECT_EQ(e["faults"][0].get<std::string>().rfind(name + " at t = ", 0), 0u) << e["faults"];
  EXPECT_EQ(e["torque_after_fault_n_m"].get<double>(), 0.0);
  EXPECT_GT(e["ticks"].get<long>(), 100);
  EXPECT_TRUE(fs::exists(a / "timeseries.csv"));
}

TEST(HdapiRun, CommErrorEndsInItsNamedFaultWithZeroTorqueAndTheDataWritten) {
  expect_named_stop("DENTSIM_HD_EMU_COMM_ERROR_AT", "hd_comm_error");
}

TEST(HdapiRun, WarmMotorsEndInTheirNamedFaultWithZeroTorqueAndTheDataWritten) {
  expect_named_stop("DENTSIM_HD_EMU_WARM_AT", "hd_warm_motors");
}

// The scheduler stalls for 0.8 s (longer than the backend's 3 x 0.1 s wait): no tick would apply
// the zero torque the fault asks for, so the backend disables force output from the waiting
// thread; the motors must not keep the last torque (they did before: 0.100 N m).
TEST(HdapiRun, SchedulerStallEndsInSchedulerStoppedWithForceOutputDisabled) {
  expect_named_stop("DENTSIM_HD_EMU_STALL_AT", "scheduler_stopped",
                    {{"DENTSIM_HD_EMU_STALL_MS", "800"}});
}

// The scheduler drops our callback (as after HD_CALLBACK_DONE) but keeps running: the last torque
// set would be held for good (0.077 N m before) unless force output is disabled.
TEST(HdapiRun, DroppedCallbackEndsInSchedulerStoppedWithForceOutputDisabled) {
  expect_named_stop("DENTSIM_HD_EMU_DONE_AT", "scheduler_stopped");
}

// `dentsim excite --device hdapi`: the calibration excitation through the backend as a device of
// unknown model (the guarded run: hold where the arm stands, approach, excitation; issue #33),
// with the device's command chain active. A device whose gravity the prior gets wrong (the
// emulator with gravity off) completes too (it faulted at t = 0 before: the prior's gravity held
// while the excitation was designed flung the arm). A fault stops the run with exit 3, one line
// naming the fault, and the log up to the stop, marked incomplete (here tick 300: during the hold,
// whatever the machine's load, so no sample).
// The emulator runs without its catch-up (DENTSIM_HD_EMU_CATCH_UP=0: a tick the loaded scheduler
// skips does not advance the simulated arm). With it, on a loaded machine (issue #32; load average
// ~6: 4 of 20 runs of this test or of the command) the excitation's near-limit torque held over a
// stalled scheduler, or its tracking PD stepped at 4 ms instead of 1 ms, flung a light gimbal
// joint into a guard (`encoder_jump` at 0.97 s; the excitation's velocity guard, joint 5 at
// 15 rad/s): the guards did their job, but whether they fire follows the machine's load. Without
// the catch-up the arm moves only in the ticks that ran, so what the test checks (the backend
// carries the excitation, the log is complete, the arm is excited) does not depend on the load:
// 7 command runs and 3 runs of this test passed at the same load. The catch-up itself is checked
// by the drill test above.
TEST(HdapiRun, ExcitationRunsThroughTheBackendAndStopsOnAFault) {
  const fs::path d = fresh("excite");
  const dentsim::testing::ScopedEnv no_catch_up("DENTSIM_HD_EMU_CATCH_UP", "0");
  for (const bool gravity : {true, false}) {
    const std::string log = (d / (gravity ? "excite.csv" : "no_gravity.csv")).string();
    if (!gravity) ::setenv("DENTSIM_HD_EMU_GRAVITY", "0", 1);
    const auto r = dentsim::testing::run_dentsim("excite --duration 2 --design-iterations 4 -o " +
                                                 log + kEmulator);
    ::unsetenv("DENTSIM_HD_EMU_GRAVITY");
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream f(log);
    std::string line;
    long rows = 0;
    double q2_min = 1e9, q2_max = -1e9;
    bool incomplete = false;
    while (std::getline(f, line)) {
      incomplete = incomplete || line.rfind("# incomplete", 0) == 0;
      if (line.empty() || line[0] == '#' || line[0] == 't') continue;
      ++rows;
      const std::size_t a = line.find(','), b = line.find(',', a + 1), c = line.find(',', b + 1);
      const double q2 = std::stod(line.substr(b + 1, c - b - 1));
      q2_min = std::min(q2_min, q2);
      q2_max = std::max(q2_max, q2);
    }
    EXPECT_FALSE(incomplete) << log;
    EXPECT_GT(rows, 500) << log;              // a sample every one or two scheduler ticks over 2 s
    EXPECT_GT(q2_max - q2_min, 0.02) << log;  // the arm was excited (rad)
  }
  const std::string bad = (d / "fault.csv").string();
  ::setenv("DENTSIM_HD_EMU_COMM_ERROR_AT", "300", 1);
  const auto e = dentsim::testing::run_dentsim("excite --duration 2 --design-iterations 4 -o " +
                                               bad + kEmulator);
  ::unsetenv("DENTSIM_HD_EMU_COMM_ERROR_AT");
  EXPECT_EQ(e.status, 3) << e.output;
  EXPECT_NE(e.output.find("excite: device fault hd_comm_error at "), std::string::npos)
      << e.output;
  EXPECT_NE(e.output.find("marked incomplete"), std::string::npos) << e.output;
  ASSERT_TRUE(fs::exists(bad));
  std::ifstream f(bad);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# incomplete: device fault hd_comm_error"), std::string::npos) << text;
}

// The device does not initialise (the emulator's init-failure switch: HD_DEVICE_FAULT): the run
// fails before its first tick, naming the call, the code and the usual causes; no report is
// written (there is no data to keep).
TEST(HdapiRun, InitFailureNamesTheCodeAndTheUsualCauses) {
  const fs::path a = fresh("init_failure");
  ::setenv("DENTSIM_HD_EMU_INIT_FAIL", "1", 1);
  const auto r =
      dentsim::testing::run_dentsim("run probe --duration 1" + kEmulator + " --out " + a.string());
  ::unsetenv("DENTSIM_HD_EMU_INIT_FAIL");
  EXPECT_EQ(r.status, 1) << r.output;
  for (const char* part :
       {"hdInitDevice", "hd_device_fault (0x0300)", "not connected", "permissions"}) {
    EXPECT_NE(r.output.find(part), std::string::npos) << part << "\n" << r.output;
  }
  EXPECT_FALSE(fs::exists(a / "report.json"));
}

TEST(HdapiRun, MissingLibraryIsNamedWithWhereItLooked) {
  const auto r = dentsim::testing::run_dentsim(
      "run probe --device hdapi --hd-library "
      "/nonexistent/libHD.so --out " +
      fresh("missing").string());
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/libHD.so"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not found"), std::string::npos) << r.output;
}

}  // namespace
