// The simulated Phantom Premium 1.5/6DoF: the MuJoCo plant generated from the device model file
// (plant/phantom_mjcf.h, one source of truth) wrapped for SimulatedPhantom, and the device
// configuration the model file implies (encoder resolution, torque limits).
//
// Device joint j (q1 yaw, q2 upper arm, q3 absolute forearm, q4..q6 gimbal) is the actuated tree
// joint phantom_actuated_tree_joint(j); the tree map G of phantom_tree_map() (elbow = q3 - q2,
// link_c = q2 - q3) is re-indexed to MuJoCo's dof order. The tip is the MJCF site "tip" (tool tip
// x1 on the roll body, R1 = the roll body's frame). The plant integrates with RK4; motor torques go
// through qfrc_applied (the simulated device saturates them itself), joint damping, Coulomb
// friction and limits are those of the model file.
#pragma once

#include "device/simulated_phantom.h"
#include "plant/mujoco_plant.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

// The plant of `p` (throws InputError if the generated MJCF does not compile).
MujocoPlant phantom_plant(const PhantomParams& p);

// Config defaults from the model file: encoder quantum 2 pi / encoder_counts_per_rev, tau_max =
// torque_limit_n_m (or, with "torque_limit": {"model": "thermal"}, the motors' peak and their
// thermal model), tau_fault = 4 tau_max, damping and friction from the MJCF.
SimulatedDeviceConfig phantom_device_config(const PhantomParams& p);

// A pose in the middle of the workspace (arm at 45 deg, gimbal centred): the midpoint of the joint
// limits, which the default model puts inside every limit.
VecX phantom_home_q(const PhantomParams& p);

}  // namespace dentsim
