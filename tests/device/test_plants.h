// Small MuJoCo plants for the simulated-device tests (independent of the Phantom model in
// plant/): a 1-DoF wheel with a closed-form response and a 6-hinge serial arm shaped like
// the Phantom (yaw, shoulder, elbow, 3-axis gimbal with an offset stylus mass).
#pragma once

#include <string>

#include "plant/mujoco_plant.h"

namespace dentsim::testing {

// A wheel of inertia I_zz = 2e-4 kg m^2 about the vertical z axis (gravity does no work on it),
// no damping or friction in the MJCF; tip at radius 0.05 m.
inline constexpr double kWheelInertia = 2e-4;

inline MujocoPlant wheel_plant() {
  MujocoPlant p;
  p.mjcf = R"(<mujoco model="wheel">
  <option timestep="0.00025" integrator="RK4"/>
  <worldbody>
    <body name="wheel">
      <joint name="q1" type="hinge" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="0.1" diaginertia="1e-4 1e-4 2e-4"/>
    </body>
  </worldbody>
</mujoco>)";
  p.tip_body = "wheel";
  p.tip_offset = Vec3(0.05, 0.0, 0.0);
  p.device_dof = {0};
  p.G = MatX::Identity(1, 1);
  return p;
}

// A 6-hinge serial arm: q1 yaw (z), q2 shoulder (y), q3 elbow (y, relative), q4..q6 gimbal
// (x, y, z); links 0.2 m and 0.17 m; joint damping 2e-3 N m s/rad (arm) and 2e-5 (gimbal),
// frictionloss 0 in the MJCF. Tip (the gimbal centre) on body "stylus".
inline MujocoPlant arm_plant() {
  MujocoPlant p;
  p.mjcf = R"(<mujoco model="arm6">
  <option timestep="0.00025" integrator="RK4" gravity="0 0 -9.81"/>
  <worldbody>
    <body name="turret">
      <joint name="q1" type="hinge" axis="0 0 1" damping="0.002"/>
      <inertial pos="0 0 0" mass="0.3" diaginertia="1.2e-3 1.2e-3 1.2e-3"/>
      <body name="upper">
        <joint name="q2" type="hinge" axis="0 1 0" damping="0.002"/>
        <inertial pos="0.08 0 0" mass="0.2" diaginertia="1e-4 8e-4 8e-4"/>
        <body name="fore" pos="0.2 0 0">
          <joint name="q3" type="hinge" axis="0 1 0" damping="0.002"/>
          <inertial pos="0.085 0 0" mass="0.05" diaginertia="1e-5 1.5e-4 1.5e-4"/>
          <body name="gimbal1" pos="0.17 0 0">
            <joint name="q4" type="hinge" axis="1 0 0" damping="2e-5"/>
            <inertial pos="0 0 0" mass="0.01" diaginertia="2e-6 2e-6 2e-6"/>
            <body name="gimbal2">
              <joint name="q5" type="hinge" axis="0 1 0" damping="2e-5"/>
              <inertial pos="0 0 0" mass="0.01" diaginertia="2e-6 2e-6 2e-6"/>
              <body name="stylus">
                <joint name="q6" type="hinge" axis="0 0 1" damping="2e-5"/>
                <inertial pos="0.01 0 -0.02" mass="0.03" diaginertia="8e-6 8e-6 2e-6"/>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)";
  p.tip_body = "stylus";
  p.tip_offset = Vec3::Zero();
  p.device_dof = {0, 1, 2, 3, 4, 5};
  p.G = MatX::Identity(6, 6);
  return p;
}

// A comfortable start pose of the arm (elbow bent, stylus hanging).
inline VecX arm_q0() {
  VecX q(6);
  q << 0.1, 0.4, -1.0, 0.2, 0.3, 0.1;
  return q;
}

}  // namespace dentsim::testing
