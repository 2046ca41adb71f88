// The loop owner: the closed loop of one servo tick against any Device (docs/design.md
// "One servo tick", "The tick as Model/Data stages"), used by the simulator, the Z-width rig,
// the wall loop and the observer report:
//
//   device.read(sample) -> pipeline.tick(sample, T_k, contacts) -> device.write(tau) ->
//   device.advance()
//
// T_k handed to the pipeline is the length of the tick about to run. A device cannot know it in
// advance: the loop uses the last measured tick length (t_k - t_k-1; the nominal period on the
// first tick), which is what a real servo loop sees and what PMI's varying-T_k form allows.
//
// Faults: a tick that returns a status other than kOk (reference/core/pipeline.h: a NaN in the
// sample, a singular device model, a full contact buffer, a failed solve, a non-finite command)
// latches that status as the loop's fault, named by tick_status_name ("tick_bad_sample", ...).
// From then on the loop commands exactly zero torque every tick (the device keeps being
// advanced, so a simulated device still moves under the hand); the owner of the loop reads
// fault() and ends the run, writing its report. Nothing in step() allocates or throws.
//
// With a safety chain (set_safety_chain; device/safety_chain.h, one definition for every backend)
// the tick's torque passes through it before the device (its watchdog fed with the previous
// tick's execution time: the CPU time the pipeline's tick took on this thread, so that being
// preempted by other programs is not read as an overrun of the tick's own work): the chain's guards
// on the sample (clock not advancing or going backwards, encoder jumps, velocity, workspace) and on
// the command latch a device fault (named after its flag: "non_monotonic_time", "encoder_jump",
// ...) with zero torque on that very tick; a fault the device itself reports after a tick (a lost
// device, its own command chain) latches too, and zero torque is written at once.
//
// Passivity observer at the device port: E_v = sum_k (tau_k - tau_g,k)^T (q_k+1 - q_k), the
// energy the virtual side put into the device through the motors, from the torque actually
// applied (after the device's command chain) less the pipeline's gravity compensation tau_g (which
// only cancels the arm's weight: its work is the change of the arm's potential energy, not
// rendering), and the measured joint angles. Exact for a torque held over the tick (zero-order
// hold) up to encoder quantisation; E_v <= 0 means passive.
#pragma once

#include <cstdint>

#include "device/device.h"
#include "device/safety_chain.h"
#include "device/virtual_supervisor.h"
#include "reference/tick.h"

namespace dentsim {

class ClosedLoop {
 public:
  // All references must outlive the loop.
  ClosedLoop(Device& device, Pipeline& pipeline, ContactProvider& contacts);

  // Reads the first sample and resets the pipeline on it (proxy at the device, at rest). A
  // sample the pipeline cannot start from latches the fault.
  void start();
  // Hand the pipeline the device's nominal period every tick instead of the measured one (an
  // ideal simulated device whose tick is exact by construction).
  void use_nominal_period(bool on) { nominal_ = on; }
  // Runs every command through `chain` (nullptr: none) and latches the device's own faults; the
  // chain must outlive the loop. Call before start().
  void set_safety_chain(SafetyChain* chain);
  // Checks every tick's result with `supervisor` (nullptr: none; device/virtual_supervisor.h)
  // before its torque goes anywhere: a violated invariant latches its named fault and the loop
  // commands zero torque on that very tick. Must outlive the loop; call before start().
  void set_supervisor(VirtualSupervisor* supervisor) { supervisor_ = supervisor; }
  // One tick: read, tick, write, advance. Returns the tick's result (valid until the next step).
  const TickResult& step();
  // The same tick in callback form, for a device whose own clock calls us (HDAPI's scheduler:
  // HdapiDevice::set_servo_function): `s` is this tick's sample, `tau_out` (sized dof) receives
  // the torque to apply over it. The previous tick is accounted on `s` first (passivity
  // observer from the torque this loop handed over, the measured tick length); a fault the device
  // has latched (faults(): an atomic read) latches here too. Nothing allocates or throws; the
  // caller must not call step() on the same loop.
  const TickResult& step_in_callback(const DeviceSample& s, VecX& tau_out);

  const DeviceSample& sample() const { return sample_; }  // latest sample (after the last step)
  double energy_virtual_j() const { return energy_; }     // E_v so far
  double last_tick_length() const { return T_; }
  long ticks() const { return ticks_; }
  // The latched tick fault (kOk while none), the latched device faults (safety chain or device;
  // kFaultNone while none), the name of the first (the tick's status name, else the lowest device
  // flag's name), and the time of the sample it was raised on.
  TickStatus fault() const { return fault_; }
  std::uint32_t device_faults() const { return device_faults_; }
  bool faulted() const {
    return fault_ != TickStatus::kOk || device_faults_ != kFaultNone ||
           supervisor_fault_ != SupervisorFault::kNone;
  }
  // The latched supervisor fault (kNone while none).
  SupervisorFault supervisor_fault() const { return supervisor_fault_; }
  const char* fault_name() const;
  double fault_time() const { return fault_t_; }
  // The torque commanded on the last step (zero once faulted) [N m].
  const VecX& commanded_torque() const { return tau_cmd_; }

 private:
  // The pipeline's tick on sample_ through the safety chain into tau_cmd_ (zero once faulted).
  const TickResult& decide();

  Device& device_;
  Pipeline& pipeline_;
  ContactProvider& contacts_;
  DeviceSample sample_, next_;
  VecX tau_cmd_;
  double T_ = 1e-3;
  double energy_ = 0.0;
  long ticks_ = 0;
  TickStatus fault_ = TickStatus::kOk;
  double fault_t_ = 0.0;
  bool nominal_ = false;
  SafetyChain* safety_ = nullptr;
  VecX tau_safe_;
  VecX tau_gravity_prev_;      // callback form: the previous tick's gravity compensation
  double last_exec_s_ = -1.0;  // the previous tick's CPU time (the watchdog's input) [s]
  std::uint32_t device_faults_ = kFaultNone;
  VirtualSupervisor* supervisor_ = nullptr;
  SupervisorFault supervisor_fault_ = SupervisorFault::kNone;
};

}  // namespace dentsim
