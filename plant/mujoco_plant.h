// A MuJoCo model of a haptic device as the simulated device sees it: the MJCF text, which body
// the hand grips, and the constant linear map between the device's joint coordinates q (n of
// them: motors and encoders) and MuJoCo's tree coordinates (nv of them, hinge/slide joints only):
//     qpos_tree = G q + qpos_offset,   qvel_tree = G qd                         (G: nv x n)
// For a closed chain (the Phantom's parallelogram) G also sets the passive tree joints; for a
// serial model it is a selection. Device joint i is the tree dof device_dof[i], and G must have
// the unit row e_i there, so that q_i = qpos_tree[device_dof[i]] (what its encoder reads) and the
// motor torque tau_i acts on that dof: power tau^T qd = Q^T qvel_tree with Q = P^T tau,
// P the selection of the device dofs (G^T P^T = (P G)^T = I). Generalised forces map back to the
// device as G^T Q (e.g. the hand's torques).
//
// MujocoDeviceModel is the analytic-free DeviceModel of such a plant (reduced dynamics
// M = G^T M_tree G, C from the Christoffel symbols of M by central differences, g = G^T
// qfrc_bias at qd = 0, friction = G^T (b qvel + f_c tanh(qvel / v_eps)) from the joints' damping b
// and frictionloss f_c). It is the "true model" the observer report uses when no analytic model
// of the plant is available, and the oracle for the simulated device's tests.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "reference/core/device_model.h"
#include "reference/core/types.h"

struct mjModel_;
struct mjData_;

namespace dentsim {

struct MujocoPlant {
  std::string mjcf;                // MJCF text
  std::string tip_body;            // body the hand grips (the tool / stylus)
  Vec3 tip_offset = Vec3::Zero();  // tool-tip point in that body's frame [m]
  std::vector<int> device_dof;     // tree dof of each device joint (size n)
  MatX G;                          // nv x n
  VecX qpos_offset;                // nv (empty = zero)
};

// RAII owner of a compiled mjModel and one mjData.
class MujocoHandle {
 public:
  // Compiles `plant.mjcf` and checks the plant against it (body name, G sizes, unit rows, hinge or
  // slide joints only). Throws InputError naming the field and what was expected.
  explicit MujocoHandle(const MujocoPlant& plant);
  ~MujocoHandle();
  MujocoHandle(const MujocoHandle&) = delete;
  MujocoHandle& operator=(const MujocoHandle&) = delete;

  mjModel_* model() const { return m_; }
  mjData_* data() const { return d_; }
  int tip_body_id() const { return tip_body_; }

 private:
  mjModel_* m_ = nullptr;
  mjData_* d_ = nullptr;
  int tip_body_ = -1;
};

class MujocoDeviceModel : public DeviceModel {
 public:
  // coulomb_velocity: v_eps [rad/s] of the smooth Coulomb term.
  explicit MujocoDeviceModel(MujocoPlant plant, double coulomb_velocity = 1e-3);
  ~MujocoDeviceModel() override;

  int dof() const override { return static_cast<int>(plant_.device_dof.size()); }
  MatX mass_matrix(const VecX& q) const override;
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override;
  VecX gravity(const VecX& q) const override;
  VecX friction_torque(const VecX& q, const VecX& qd) const override;

  // Sets the gravity of the model (default: the MJCF's) [m/s^2], e.g. zero for a
  // gravity-compensated device.
  void set_gravity(const Vec3& g);
  // Overrides joint damping [N m s/rad] and frictionloss [N m] of the device dofs (the simulated
  // device's configuration); empty vectors keep the MJCF values.
  void set_device_friction(const VecX& damping, const VecX& frictionloss);

 private:
  VecX tree_qpos(const VecX& q) const;
  MujocoPlant plant_;
  double coulomb_velocity_;
  std::unique_ptr<MujocoHandle> h_;
};

}  // namespace dentsim
