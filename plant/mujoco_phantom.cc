#include "plant/mujoco_phantom.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "reference/phantom/phantom_model.h"

namespace dentsim {

mjModel* load_mjcf_from_string(const std::string& xml, const std::string& name) {
  auto vfs = std::make_unique<mjVFS>();  // large struct: keep it off the stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(xml.size())) != 0) {
    throw std::runtime_error("MuJoCo VFS: cannot create '" + name + "'");
  }
  const int i = mj_findFileVFS(vfs.get(), name.c_str());
  std::memcpy(vfs->filedata[i], xml.data(), xml.size());
  char err[1000] = "";
  mjModel* m = mj_loadXML(name.c_str(), vfs.get(), err, sizeof err);
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error("MuJoCo could not load the Phantom MJCF: " + std::string(err));
  return m;
}

MujocoPhantom::MujocoPhantom(const PhantomParams& params, const PhantomMjcfOptions& options)
    : MujocoPhantom(phantom_mjcf(params, options)) {}

MujocoPhantom::MujocoPhantom(const std::string& mjcf_xml) {
  m_ = load_mjcf_from_string(mjcf_xml, "phantom.xml");
  d_ = mj_makeData(m_);
  if (!d_) {
    mj_deleteModel(m_);
    m_ = nullptr;
    throw std::runtime_error("MuJoCo: mj_makeData failed for the Phantom model");
  }
  try {
    bind_names();
  } catch (...) {
    release();
    throw;
  }
  mj_forward(m_, d_);
}

MujocoPhantom::~MujocoPhantom() { release(); }

MujocoPhantom::MujocoPhantom(MujocoPhantom&& other) noexcept { *this = std::move(other); }

MujocoPhantom& MujocoPhantom::operator=(MujocoPhantom&& other) noexcept {
  if (this != &other) {
    release();
    m_ = std::exchange(other.m_, nullptr);
    d_ = std::exchange(other.d_, nullptr);
    std::memcpy(qadr_, other.qadr_, sizeof qadr_);
    std::memcpy(dadr_, other.dadr_, sizeof dadr_);
    std::memcpy(motor_, other.motor_, sizeof motor_);
    tip_site_ = other.tip_site_;
  }
  return *this;
}

void MujocoPhantom::release() {
  if (d_) mj_deleteData(d_);
  if (m_) mj_deleteModel(m_);
  d_ = nullptr;
  m_ = nullptr;
}

void MujocoPhantom::bind_names() {
  if (m_->nv != kPhantomTreeDof) {
    throw std::runtime_error("Phantom MJCF: expected " + std::to_string(kPhantomTreeDof) +
                             " degrees of freedom, got " + std::to_string(m_->nv));
  }
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    const int id = mj_name2id(m_, mjOBJ_JOINT, kPhantomMjcfJoints[i]);
    if (id < 0)
      throw std::runtime_error(std::string("Phantom MJCF: no joint ") + kPhantomMjcfJoints[i]);
    qadr_[i] = m_->jnt_qposadr[id];
    dadr_[i] = m_->jnt_dofadr[id];
  }
  for (int j = 0; j < 6; ++j) {
    motor_[j] = mj_name2id(m_, mjOBJ_ACTUATOR, kPhantomMjcfMotors[j]);
    if (motor_[j] < 0)
      throw std::runtime_error(std::string("Phantom MJCF: no motor ") + kPhantomMjcfMotors[j]);
  }
  tip_site_ = mj_name2id(m_, mjOBJ_SITE, kPhantomMjcfTipSite);
  if (tip_site_ < 0) throw std::runtime_error("Phantom MJCF: no site tip");
}

void MujocoPhantom::set_state(const Vec6& q, const Vec6& qd) {
  const Eigen::Matrix<double, kPhantomTreeDof, 6> G = phantom_tree_map();
  const Eigen::Matrix<double, kPhantomTreeDof, 1> th = G * q;
  const Eigen::Matrix<double, kPhantomTreeDof, 1> thd = G * qd;
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    d_->qpos[qadr_[i]] = th(i);
    d_->qvel[dadr_[i]] = thd(i);
  }
  mj_forward(m_, d_);
}

Vec6 MujocoPhantom::q() const {
  Vec6 q;
  for (int j = 0; j < 6; ++j) q(j) = d_->qpos[qadr_[phantom_actuated_tree_joint(j)]];
  return q;
}

Vec6 MujocoPhantom::qd() const {
  Vec6 v;
  for (int j = 0; j < 6; ++j) v(j) = d_->qvel[dadr_[phantom_actuated_tree_joint(j)]];
  return v;
}

void MujocoPhantom::set_torque(const Vec6& tau) {
  for (int j = 0; j < 6; ++j) d_->ctrl[motor_[j]] = tau(j);
}

void MujocoPhantom::step() { mj_step(m_, d_); }

namespace {
using TreeMat = Eigen::Matrix<double, kPhantomTreeDof, kPhantomTreeDof, Eigen::RowMajor>;
}

Mat6 MujocoPhantom::reduced_mass_matrix() {
  mj_kinematics(m_, d_);
  mj_comPos(m_, d_);
  mj_crb(m_, d_);
  TreeMat Mt_dofs;
  mj_fullM(m_, Mt_dofs.data(), d_->qM);
  // Permute MuJoCo's dof order into tree-joint order before reducing.
  Eigen::Matrix<double, kPhantomTreeDof, kPhantomTreeDof> Mt;
  for (int a = 0; a < kPhantomTreeDof; ++a) {
    for (int b = 0; b < kPhantomTreeDof; ++b) Mt(a, b) = Mt_dofs(dadr_[a], dadr_[b]);
  }
  const Eigen::Matrix<double, kPhantomTreeDof, 6> G = phantom_tree_map();
  return G.transpose() * Mt * G;
}

Vec6 MujocoPhantom::reduced_bias() {
  mjtNum saved[3];
  mju_copy3(saved, m_->opt.gravity);
  mju_zero3(m_->opt.gravity);
  mj_kinematics(m_, d_);
  mj_comPos(m_, d_);
  mj_comVel(m_, d_);
  std::vector<mjtNum> bias(m_->nv);
  mj_rne(m_, d_, 0, bias.data());
  mju_copy3(m_->opt.gravity, saved);
  const Eigen::Matrix<double, kPhantomTreeDof, 6> G = phantom_tree_map();
  Eigen::Matrix<double, kPhantomTreeDof, 1> bt;
  for (int i = 0; i < kPhantomTreeDof; ++i) bt(i) = bias[dadr_[i]];
  return G.transpose() * bt;
}

Vec6 MujocoPhantom::reduced_gravity() {
  std::vector<mjtNum> qvel(d_->qvel, d_->qvel + m_->nv);
  mju_zero(d_->qvel, m_->nv);
  mj_kinematics(m_, d_);
  mj_comPos(m_, d_);
  mj_comVel(m_, d_);
  std::vector<mjtNum> bias(m_->nv);
  mj_rne(m_, d_, 0, bias.data());
  mju_copy(d_->qvel, qvel.data(), m_->nv);
  mj_comVel(m_, d_);
  const Eigen::Matrix<double, kPhantomTreeDof, 6> G = phantom_tree_map();
  Eigen::Matrix<double, kPhantomTreeDof, 1> gt;
  for (int i = 0; i < kPhantomTreeDof; ++i) gt(i) = bias[dadr_[i]];
  return G.transpose() * gt;
}

Pose MujocoPhantom::tip_pose() {
  mj_kinematics(m_, d_);
  Pose pose;
  for (int r = 0; r < 3; ++r) {
    pose.x(r) = d_->site_xpos[3 * tip_site_ + r];
    for (int c = 0; c < 3; ++c) pose.R(r, c) = d_->site_xmat[9 * tip_site_ + 3 * r + c];
  }
  return pose;
}

Mat6 MujocoPhantom::tip_jacobian() {
  mj_kinematics(m_, d_);
  mj_comPos(m_, d_);
  std::vector<mjtNum> jacp(3 * m_->nv), jacr(3 * m_->nv);
  mj_jacSite(m_, d_, jacp.data(), jacr.data(), tip_site_);
  Eigen::Matrix<double, 6, kPhantomTreeDof> Jt;
  for (int r = 0; r < 3; ++r) {
    for (int i = 0; i < kPhantomTreeDof; ++i) {
      Jt(r, i) = jacp[r * m_->nv + dadr_[i]];
      Jt(3 + r, i) = jacr[r * m_->nv + dadr_[i]];
    }
  }
  const Pose pose = tip_pose();
  Jt.bottomRows<3>() = pose.R.transpose() * Jt.bottomRows<3>();  // w world -> body
  return Jt * phantom_tree_map();
}

double MujocoPhantom::closure_error() const {
  const double elbow = d_->qpos[qadr_[kForearm]];
  const double link_c = d_->qpos[qadr_[kParallelLink]];
  const double q2 = d_->qpos[qadr_[kUpperArm]];
  const double q3 = d_->qpos[qadr_[kCrank]];
  return std::max(std::abs(link_c + elbow), std::abs(q3 - q2 - elbow));
}

}  // namespace dentsim
