#include "device/phantom_device.h"

#include <mujoco/mujoco.h>

#include <numbers>
#include <string>

#include "plant/mujoco_phantom.h"
#include "plant/phantom_mjcf.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {

MujocoPlant phantom_plant(const PhantomParams& p) {
  PhantomMjcfOptions opt;
  opt.integrator = "RK4";
  opt.torque_saturation = false;  // SimulatedPhantom saturates (and reports) the torque
  MujocoPlant plant;
  plant.mjcf = phantom_mjcf(p, opt);
  mjModel* m = nullptr;
  try {
    m = load_mjcf_from_string(plant.mjcf, "phantom.xml");
  } catch (const std::exception& e) {
    throw InputError(std::string("phantom plant: generated MJCF does not load: ") + e.what());
  }
  const int site = mj_name2id(m, mjOBJ_SITE, kPhantomMjcfTipSite);
  if (site < 0) {
    mj_deleteModel(m);
    throw InputError("phantom plant: the MJCF has no site 'tip'");
  }
  plant.tip_body = mj_id2name(m, mjOBJ_BODY, m->site_bodyid[site]);
  for (int i = 0; i < 3; ++i) plant.tip_offset[i] = m->site_pos[3 * site + i];
  const auto G8 = phantom_tree_map();
  plant.G = MatX::Zero(m->nv, 6);
  int dof_of_tree[kPhantomTreeDof];
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    const int j = mj_name2id(m, mjOBJ_JOINT, kPhantomMjcfJoints[i]);
    if (j < 0) {
      mj_deleteModel(m);
      throw InputError(std::string("phantom plant: the MJCF has no joint '") +
                       kPhantomMjcfJoints[i] + "'");
    }
    dof_of_tree[i] = m->jnt_dofadr[j];
    plant.G.row(dof_of_tree[i]) = G8.row(i);
  }
  for (int d = 0; d < 6; ++d)
    plant.device_dof.push_back(dof_of_tree[phantom_actuated_tree_joint(d)]);
  plant.qpos_offset = VecX::Zero(m->nv);
  mj_deleteModel(m);
  return plant;
}

SimulatedDeviceConfig phantom_device_config(const PhantomParams& p) {
  SimulatedDeviceConfig c;
  c.encoder_quantum = VecX(6);
  for (int j = 0; j < 6; ++j)
    c.encoder_quantum[j] = 2.0 * std::numbers::pi / p.encoder_counts_per_rev[j];
  c.tau_max = phantom_torque_clamp(p);  // torque_limit_n_m, or the motors' peak (thermal)
  c.tau_fault = 4.0 * c.tau_max;
  c.torque_limit = p.torque_limit;
  c.gravity = p.gravity_on;
  c.coulomb_velocity = p.coulomb_smoothing_rad_s;
  c.coulomb_sign.assign(p.coulomb_sign.begin(), p.coulomb_sign.end());
  return c;
}

VecX phantom_home_q(const PhantomParams& p) { return 0.5 * (p.q_min_rad + p.q_max_rad); }

}  // namespace dentsim
