#include "plant/mujoco_plant.h"

#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "reference/core/io.h"

namespace dentsim {
namespace {

mjModel* compile_mjcf(const std::string& xml) {
  // MuJoCo 2.2.2 loads MJCF text through a virtual file system.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "dentsim_plant.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(xml.size())) != 0) {
    throw InputError("MuJoCo plant: cannot create the in-memory MJCF file");
  }
  const int idx = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[idx], xml.data(), xml.size());
  char err[1024] = {0};
  mjModel* m = mj_loadXML(name, vfs.get(), err, sizeof(err));
  mj_deleteVFS(vfs.get());
  if (m == nullptr) throw InputError(std::string("MuJoCo plant: MJCF does not compile: ") + err);
  return m;
}

}  // namespace

MujocoHandle::MujocoHandle(const MujocoPlant& plant) {
  m_ = compile_mjcf(plant.mjcf);
  auto fail = [this](const std::string& msg) {
    mj_deleteModel(m_);
    m_ = nullptr;
    throw InputError("MuJoCo plant: " + msg);
  };
  for (int j = 0; j < m_->njnt; ++j) {
    if (m_->jnt_type[j] != mjJNT_HINGE && m_->jnt_type[j] != mjJNT_SLIDE) {
      fail("joint " + std::to_string(j) + " is not a hinge or slide; expected only those");
    }
  }
  const int nv = m_->nv;
  const int n = static_cast<int>(plant.device_dof.size());
  if (n < 1) fail("device_dof is empty, expected one tree dof per device joint");
  if (plant.G.rows() != nv || plant.G.cols() != n) {
    fail("G is " + std::to_string(plant.G.rows()) + "x" + std::to_string(plant.G.cols()) +
         ", expected nv x n = " + std::to_string(nv) + "x" + std::to_string(n));
  }
  if (plant.qpos_offset.size() != 0 && plant.qpos_offset.size() != nv) {
    fail("qpos_offset has " + std::to_string(plant.qpos_offset.size()) +
         " entries, expected 0 or " + std::to_string(nv));
  }
  for (int i = 0; i < n; ++i) {
    const int dof = plant.device_dof[i];
    if (dof < 0 || dof >= nv) fail("device_dof[" + std::to_string(i) + "] out of range");
    const VecX row = plant.G.row(dof).transpose();
    if (row != VecX::Unit(n, i)) {
      fail("row device_dof[" + std::to_string(i) + "] of G is not the unit row e_" +
           std::to_string(i));
    }
  }
  tip_body_ = mj_name2id(m_, mjOBJ_BODY, plant.tip_body.c_str());
  if (tip_body_ < 0) fail("tip_body '" + plant.tip_body + "' is not a body of the MJCF");
  d_ = mj_makeData(m_);
}

MujocoHandle::~MujocoHandle() {
  if (d_ != nullptr) mj_deleteData(d_);
  if (m_ != nullptr) mj_deleteModel(m_);
}

MujocoDeviceModel::MujocoDeviceModel(MujocoPlant plant, double coulomb_velocity)
    : plant_(std::move(plant)), coulomb_velocity_(coulomb_velocity) {
  h_ = std::make_unique<MujocoHandle>(plant_);
  if (plant_.qpos_offset.size() == 0) plant_.qpos_offset = VecX::Zero(h_->model()->nv);
}

MujocoDeviceModel::~MujocoDeviceModel() = default;

void MujocoDeviceModel::set_gravity(const Vec3& g) {
  for (int i = 0; i < 3; ++i) h_->model()->opt.gravity[i] = g[i];
}

void MujocoDeviceModel::set_device_friction(const VecX& damping, const VecX& frictionloss) {
  mjModel* m = h_->model();
  for (int i = 0; i < dof(); ++i) {
    if (damping.size() == dof()) m->dof_damping[plant_.device_dof[i]] = damping[i];
    if (frictionloss.size() == dof()) m->dof_frictionloss[plant_.device_dof[i]] = frictionloss[i];
  }
}

VecX MujocoDeviceModel::tree_qpos(const VecX& q) const { return plant_.G * q + plant_.qpos_offset; }

MatX MujocoDeviceModel::mass_matrix(const VecX& q) const {
  const mjModel* m = h_->model();
  mjData* d = h_->data();
  const int nv = m->nv;
  const VecX qt = tree_qpos(q);
  for (int j = 0; j < nv; ++j) d->qpos[m->jnt_qposadr[m->dof_jntid[j]]] = qt[j];
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_crb(m, d);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Mt(nv, nv);
  mj_fullM(m, Mt.data(), d->qM);
  return plant_.G.transpose() * Mt * plant_.G;  // M = G^T M_tree G
}

MatX MujocoDeviceModel::coriolis_matrix(const VecX& q, const VecX& qd) const {
  // C_ij = sum_k 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) qd_k (Christoffel symbols).
  const int n = dof();
  const double h = 1e-6;
  std::vector<MatX> dM(n);
  for (int k = 0; k < n; ++k) {
    VecX qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    dM[k] = (mass_matrix(qp) - mass_matrix(qm)) / (2.0 * h);
  }
  MatX C = MatX::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      double c = 0.0;
      for (int k = 0; k < n; ++k) c += 0.5 * (dM[k](i, j) + dM[j](i, k) - dM[i](j, k)) * qd[k];
      C(i, j) = c;
    }
  }
  return C;
}

VecX MujocoDeviceModel::gravity(const VecX& q) const {
  const mjModel* m = h_->model();
  mjData* d = h_->data();
  const int nv = m->nv;
  const VecX qt = tree_qpos(q);
  for (int j = 0; j < nv; ++j) {
    d->qpos[m->jnt_qposadr[m->dof_jntid[j]]] = qt[j];
    d->qvel[j] = 0.0;
  }
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_comVel(m, d);
  mj_rne(m, d, 0, d->qfrc_bias);  // qd = 0: the bias force is the gravity force
  VecX Q = Eigen::Map<const VecX>(d->qfrc_bias, nv);
  return plant_.G.transpose() * Q;  // g = G^T g_tree
}

VecX MujocoDeviceModel::friction_torque(const VecX& /*q*/, const VecX& qd) const {
  const mjModel* m = h_->model();
  const VecX vt = plant_.G * qd;
  VecX Q(m->nv);
  for (int j = 0; j < m->nv; ++j) {
    Q[j] =
        m->dof_damping[j] * vt[j] + m->dof_frictionloss[j] * std::tanh(vt[j] / coulomb_velocity_);
  }
  return plant_.G.transpose() * Q;
}

}  // namespace dentsim
