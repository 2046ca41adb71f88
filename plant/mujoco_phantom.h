// The MuJoCo 2.2.2 model of the Phantom (plant/phantom_mjcf.h) loaded and wrapped: RAII
// ownership of mjModel/mjData, and the reduction of tree quantities to the device coordinates
// q = (q1..q6) through the constant map theta = G q (phantom_tree_map(), docs/device_facts.md §4):
//     M_red = G^T M_tree G,  bias_red = G^T qfrc_bias,  J_red = J_tree G.
// Used by the cross-check (validation/crosscheck_device.h) and by the simulated device (device/).
// Units: SI; the tip twist is V = [v (world); w (body)] as everywhere in dentsim.
#pragma once

#include <mujoco/mujoco.h>

#include <string>

#include "plant/phantom_mjcf.h"
#include "reference/core/types.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

class MujocoPhantom {
 public:
  // Generates the MJCF from `params` and loads it (from memory, via MuJoCo's VFS).
  explicit MujocoPhantom(const PhantomParams& params, const PhantomMjcfOptions& options = {});
  // Loads MJCF text that follows phantom_mjcf's naming (joints q1, q2, elbow, q3, link_c,
  // q4..q6; motors tau1..tau6; site tip). Throws std::runtime_error with MuJoCo's message.
  explicit MujocoPhantom(const std::string& mjcf_xml);
  ~MujocoPhantom();
  MujocoPhantom(const MujocoPhantom&) = delete;
  MujocoPhantom& operator=(const MujocoPhantom&) = delete;
  MujocoPhantom(MujocoPhantom&& other) noexcept;
  MujocoPhantom& operator=(MujocoPhantom&& other) noexcept;

  const mjModel* model() const { return m_; }
  mjModel* model() { return m_; }
  const mjData* data() const { return d_; }
  mjData* data() { return d_; }

  // qpos = G q, qvel = G qd (the chain exactly closed), act/ctrl untouched, then mj_forward.
  void set_state(const Vec6& q, const Vec6& qd);
  // Device coordinates read back from the actuated tree joints (q1, q2, q3, q4..q6).
  Vec6 q() const;
  Vec6 qd() const;
  // Motor torques [N m] (ctrl, saturated by MuJoCo at the torque limits if so generated).
  void set_torque(const Vec6& tau);
  void step();  // one mj_step of options().timestep
  double time() const { return d_->time; }

  // Reduced quantities at the current state (each calls the MuJoCo stages it needs).
  Mat6 reduced_mass_matrix();  // G^T M G (armature included)
  Vec6 reduced_bias();         // C(q, qd) qd: G^T qfrc_bias evaluated with gravity off
  Vec6 reduced_gravity();      // g(q): G^T qfrc_bias evaluated with qvel = 0
  Pose tip_pose();             // site "tip": x1 (world), R1
  Mat6 tip_jacobian();         // V1 = [v1 (world); w1 (body)] = J qd

  // Largest violation of the two parallelogram equalities [rad] (0 when exactly closed).
  double closure_error() const;

 private:
  void bind_names();
  void release();

  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  int qadr_[8] = {};   // qpos address of tree joint i
  int dadr_[8] = {};   // dof address of tree joint i
  int motor_[6] = {};  // actuator id of device joint j
  int tip_site_ = -1;
};

// Loads MJCF text from memory through a VFS; returns the model or throws std::runtime_error with
// MuJoCo's error message.
mjModel* load_mjcf_from_string(const std::string& xml, const std::string& name = "model.xml");

}  // namespace dentsim
