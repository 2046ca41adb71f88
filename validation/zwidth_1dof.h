// The 1-DoF testbed of the Z-width experiment (issue #7): an ideal rigid-body haptic device that
// can only translate along the world z axis, run as sampled-data hardware behind the Device
// interface (device/device.h), so the experiment drives it through exactly the same code paths
// as the simulated Phantom: ClosedLoop -> ReferencePipeline (6-DoF, with the rigid-body device
// model of reference/rigid_body_device.h) -> Device command chain.
//
// Coordinates (those of RigidBodyDevice): q = [x (world tip position, m); theta (rotation
// vector)], so J1 = I at theta = 0 and joint torques are tip forces [N] on q1..q3. Only q3 = z
// moves; the other five coordinates are held by an ideal constraint (their commanded torques do
// no work and are ignored). Units SI.
//
// Plant along z, per tick k of length T_k with the applied force u_k held (zero-order hold):
//     (m_d + m_h) z'' = u_k - b_d z' - f_c tanh(z' / v_eps) + f_h(t, z, z')
// integrated with `substeps` RK4 steps; f_h is the z component of the scripted hand's wrench
// (device/scripted_hand.h, evaluated from the true tip state) and m_h its mass while attached.
// What the driver reports (as the simulated Phantom does): z quantised to the encoder quantum
// Delta (z_meas = Delta floor(z / Delta)), velocity from the quantised positions by the driver's
// estimator (device/velocity_estimator.h), the device clock t_k. The command chain is the
// shared condition_command (finite check -> fault threshold -> saturation at +-force_limit).
// Tick jitter: T_k uniform on [T - a, T + a] from a seeded std::mt19937_64.
#pragma once

#include <cstdint>
#include <random>

#include "device/device.h"
#include "device/scripted_hand.h"
#include "device/velocity_estimator.h"
#include "reference/rigid_body_device.h"

namespace dentsim {

struct AxisDeviceParams {
  double mass = 0.136;               // m_d [kg], apparent mass along the axis
  double damping = 0.0125;           // b_d [N s/m], physical (viscous) damping along the axis
  double coulomb = 0.0;              // f_c [N]
  double coulomb_velocity = 1e-3;    // v_eps [m/s]
  double force_limit = 8.5;          // saturation [N] (fault threshold 4x)
  double quantum = 2.3e-5;           // encoder quantum Delta along the axis [m] (0 = exact)
  double period = 1e-3;              // nominal servo tick T [s]
  double jitter_half_width = 0.0;    // a [s], uniform jitter of T_k
  std::uint64_t seed = 1;            // jitter seed
  int substeps = 8;                  // RK4 steps per tick
  VelocityEstimatorParams velocity;  // driver's velocity estimator
};

class AxisDevice : public Device {
 public:
  // Starts at rest with the tip at `start` (only start.z() may change later), t = 0. Throws
  // InputError naming the field if a parameter is out of range.
  AxisDevice(AxisDeviceParams params, const Vec3& start);

  const DeviceCapabilities& capabilities() const override { return caps_; }
  const DeviceLimits& limits() const override { return limits_; }
  void read(DeviceSample& out) const override;
  void write(const VecX& tau) override;
  void advance() override;
  const VecX& applied_torque() const override { return tau_applied_; }
  std::uint32_t faults() const override { return faults_; }
  void clear_faults() override { faults_ = kFaultNone; }

  // Attaches the scripted hand (its mass joins the device) or releases it (nullptr). The hand
  // must outlive its attachment.
  void set_hand(const ScriptedHand* hand) { hand_ = hand; }

  // Ground truth.
  double true_z() const { return z_; }
  double true_vz() const { return v_; }
  Pose tip_pose() const;
  double time() const { return t_; }
  const AxisDeviceParams& params() const { return p_; }

 private:
  double accel(double z, double v, double t) const;
  void sample_encoders();

  AxisDeviceParams p_;
  Vec3 start_;
  DeviceCapabilities caps_;
  DeviceLimits limits_;
  VelocityEstimator vel_;
  std::mt19937_64 rng_;
  const ScriptedHand* hand_ = nullptr;
  double z_ = 0.0, v_ = 0.0, t_ = 0.0;
  VecX q_meas_, tau_applied_;
  std::uint32_t faults_ = kFaultNone;
};

// The pipeline's model of the 1-DoF device: RigidBodyDevice with mass `mass` and translational
// damping `damping` (the values the observer believes; perturb them for the model-error test).
RigidBodyDeviceParams axis_device_model_params(double mass, double damping);

}  // namespace dentsim
