#include "device/simulated_phantom.h"

#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

using RowMat3X = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>;

void check_size(const VecX& v, int n, const char* field) {
  if (v.size() != 0 && v.size() != n) {
    throw InputError(std::string("simulated device: config.") + field + " has " +
                     std::to_string(v.size()) + " entries, expected 0 (default) or " +
                     std::to_string(n));
  }
}

void check_nonneg(const VecX& v, const char* field) {
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (!(std::isfinite(v[i]) && v[i] >= 0.0)) {
      throw InputError(std::string("simulated device: config.") + field + "[" + std::to_string(i) +
                       "] = " + std::to_string(v[i]) + ", expected a finite value >= 0");
    }
  }
}

void check_jitter(const TickJitter& j) {
  auto bad = [](const std::string& msg) { throw InputError("simulated device: jitter." + msg); };
  if (!(std::isfinite(j.period) && j.period > 0.0)) bad("period must be finite and > 0");
  switch (j.kind) {
    case TickJitterKind::kNone:
      break;
    case TickJitterKind::kUniform:
      if (!(j.half_width >= 0.0 && j.half_width < j.period)) {
        bad("half_width = " + std::to_string(j.half_width) + ", expected in [0, period)");
      }
      break;
    case TickJitterKind::kNormal:
      if (!(std::isfinite(j.sigma) && j.sigma >= 0.0)) bad("sigma must be finite and >= 0");
      break;
    case TickJitterKind::kTrace:
      if (j.trace.empty()) bad("trace is empty, expected >= 1 tick length");
      for (double T : j.trace) {
        if (!std::isfinite(T)) bad("trace has a non-finite tick length");
      }
      break;
  }
}

}  // namespace

VecX phantom_drive_ratios() {
  VecX r(6);
  r << 13.3, 11.2, 11.2, 1.0, 1.0, 1.0;
  return r;
}

VecX phantom_tau_max() {
  VecX t(6);
  t << 0.400, 0.350, 0.200, 0.188, 0.188, 0.048;
  return t;
}

VecX encoder_quantum(int counts_per_rev, int quadrature, const VecX& drive_ratio) {
  if (counts_per_rev < 1 || quadrature < 1) {
    throw InputError("simulated device: counts_per_rev and quadrature must be >= 1");
  }
  VecX d(drive_ratio.size());
  for (Eigen::Index i = 0; i < d.size(); ++i) {
    if (!(drive_ratio[i] > 0.0)) {
      throw InputError("simulated device: drive_ratio[" + std::to_string(i) +
                       "] = " + std::to_string(drive_ratio[i]) + ", expected > 0");
    }
    d[i] = 2.0 * std::numbers::pi / (quadrature * counts_per_rev * drive_ratio[i]);
  }
  return d;
}

SimulatedPhantom::SimulatedPhantom(const MujocoPlant& plant, SimulatedDeviceConfig config,
                                   const VecX& q0)
    : plant_(plant),
      cfg_(std::move(config)),
      vel_(std::max<int>(1, static_cast<int>(plant.device_dof.size())), cfg_.velocity),
      rng_(cfg_.jitter.seed) {
  h_ = std::make_unique<MujocoHandle>(plant_);
  mjModel* m = h_->model();
  mjData* d = h_->data();
  const int n = static_cast<int>(plant_.device_dof.size());
  const int nv = m->nv;
  if (plant_.qpos_offset.size() == 0) plant_.qpos_offset = VecX::Zero(nv);
  if (q0.size() != n) {
    throw InputError("simulated device: q0 has " + std::to_string(q0.size()) +
                     " entries, expected " + std::to_string(n));
  }
  if (!(std::isfinite(cfg_.max_substep) && cfg_.max_substep > 0.0)) {
    throw InputError("simulated device: config.max_substep must be finite and > 0");
  }
  check_size(cfg_.drive_ratio, n, "drive_ratio");
  check_size(cfg_.encoder_quantum, n, "encoder_quantum");
  check_size(cfg_.tau_max, n, "tau_max");
  check_size(cfg_.tau_fault, n, "tau_fault");
  check_size(cfg_.damping, n, "damping");
  check_size(cfg_.frictionloss, n, "frictionloss");
  check_nonneg(cfg_.encoder_quantum, "encoder_quantum");
  check_nonneg(cfg_.tau_max, "tau_max");
  check_nonneg(cfg_.tau_fault, "tau_fault");
  check_nonneg(cfg_.damping, "damping");
  check_nonneg(cfg_.frictionloss, "frictionloss");
  check_jitter(cfg_.jitter);

  // Integrator, gravity, damping and friction of the plant.
  if (cfg_.rk4) m->opt.integrator = mjINT_RK4;
  if (!cfg_.gravity) {
    for (int i = 0; i < 3; ++i) m->opt.gravity[i] = 0.0;
  }
  for (int i = 0; i < n; ++i) {
    const int dof = plant_.device_dof[i];
    if (cfg_.damping.size() == n) m->dof_damping[dof] = cfg_.damping[i];
    if (cfg_.frictionloss.size() == n) m->dof_frictionloss[dof] = cfg_.frictionloss[i];
  }
  for (int j = 0; j < nv; ++j) {
    if (!cfg_.damping_on) m->dof_damping[j] = 0.0;
    if (!cfg_.friction_on) m->dof_frictionloss[j] = 0.0;
  }
  if (cfg_.friction_law == SimulatedDeviceConfig::FrictionLaw::kTanh) {
    if (cfg_.coulomb_velocity.size() == 0) cfg_.coulomb_velocity = VecX::Constant(n, 0.01);
    check_size(cfg_.coulomb_velocity, n, "coulomb_velocity");
    for (int i = 0; i < n; ++i) {
      if (!(std::isfinite(cfg_.coulomb_velocity[i]) && cfg_.coulomb_velocity[i] >= 0.0)) {
        throw InputError("simulated device: config.coulomb_velocity must be finite and >= 0 (joint " +
                         std::to_string(i + 1) + ")");
      }
    }
    if (cfg_.coulomb_sign.empty()) cfg_.coulomb_sign.assign(n, CoulombSign::kTanh);
    if (static_cast<int>(cfg_.coulomb_sign.size()) != n) {
      throw InputError("simulated device: config.coulomb_sign has " +
                       std::to_string(cfg_.coulomb_sign.size()) + " entries, expected " +
                       std::to_string(n));
    }
    coulomb_tanh_ = VecX::Zero(n);
    for (int i = 0; i < n; ++i) {
      const int dof = plant_.device_dof[i];
      coulomb_tanh_[i] = m->dof_frictionloss[dof];
      m->dof_frictionloss[dof] = 0.0;
    }
  }

  // Encoders.
  if (!cfg_.quantize) {
    caps_.encoder_quantum = VecX::Zero(n);
  } else if (cfg_.encoder_quantum.size() == n) {
    caps_.encoder_quantum = cfg_.encoder_quantum;
  } else {
    VecX ratio = cfg_.drive_ratio;
    if (ratio.size() == 0) ratio = n == 6 ? phantom_drive_ratios() : VecX::Ones(n);
    caps_.encoder_quantum = encoder_quantum(cfg_.counts_per_rev, cfg_.quadrature, ratio);
  }
  caps_.dof = n;
  caps_.measures_velocity = false;
  caps_.has_force_sensor = false;
  caps_.simulated = true;
  caps_.nominal_period = cfg_.jitter.period;
  caps_.velocity_lowpass_hz = cfg_.velocity.filter == VelocityFilter::kFirstOrderLowPass
                                  ? cfg_.velocity.cutoff_hz
                                  : 0.0;

  // Limits.
  limits_.tau_max =
      cfg_.tau_max.size() == n ? cfg_.tau_max : (n == 6 ? phantom_tau_max() : VecX::Ones(n));
  limits_.tau_fault = cfg_.tau_fault.size() == n ? cfg_.tau_fault : VecX(4.0 * limits_.tau_max);
  limits_.max_joint_step = cfg_.max_joint_step;
  if (cfg_.torque_limit.model == TorqueLimitModel::kThermal) {
    if (n != 6) {
      throw InputError("simulated device: config.torque_limit thermal needs 6 joints, the plant has " +
                       std::to_string(n));
    }
    thermal_ = MotorThermal(cfg_.torque_limit);
  }

  // Tip body inertia as compiled (restored when the hand is released).
  const int b = h_->tip_body_id();
  body_mass0_ = m->body_mass[b];
  for (int i = 0; i < 3; ++i) {
    body_ipos0_[i] = m->body_ipos[3 * b + i];
    body_inertia0_[i] = m->body_inertia[3 * b + i];
  }
  for (int i = 0; i < 4; ++i) body_iquat0_[i] = m->body_iquat[4 * b + i];
  body_sameframe0_ = m->body_sameframe[b];
  body_simple0_ = m->body_simple[b];
  dof_simplenum0_.assign(m->dof_simplenum, m->dof_simplenum + nv);
  m->opt.enableflags |= mjENBL_ENERGY;

  // Buffers (no allocation per tick).
  q_true_ = VecX::Zero(n);
  qd_true_ = VecX::Zero(n);
  q_meas_ = VecX::Zero(n);
  q_meas_prev_ = VecX::Zero(n);
  tau_applied_ = VecX::Zero(n);
  tau_hand_avg_ = VecX::Zero(n);
  tau_hand_sub_ = VecX::Zero(n);
  tau_hand_inertia_ = VecX::Zero(n);
  Q_tree_ = VecX::Zero(nv);
  jacp_.assign(3 * nv, 0.0);
  jacr_.assign(3 * nv, 0.0);
  jacp_prev_.assign(3 * nv, 0.0);
  jacr_prev_.assign(3 * nv, 0.0);
  scratch_ = mj_makeData(m);

  // Initial state: q0 at rest, t = 0.
  const VecX qt = plant_.G * q0 + plant_.qpos_offset;
  for (int j = 0; j < nv; ++j) {
    d->qpos[m->jnt_qposadr[m->dof_jntid[j]]] = qt[j];
    d->qvel[j] = 0.0;
  }
  d->time = 0.0;
  mj_forward(m, d);
  refresh_truth();
  sample_encoders();
  q_meas_prev_ = q_meas_;
  vel_.reset(q_meas_, 0.0, VecX::Zero(n));
  update_tip_kinematics();
}

SimulatedPhantom::~SimulatedPhantom() {
  if (scratch_ != nullptr) mj_deleteData(scratch_);
}

const mjModel_* SimulatedPhantom::model() const { return h_->model(); }

double SimulatedPhantom::physics_time() const { return h_->data()->time; }

void SimulatedPhantom::read(DeviceSample& out) const {
  out.q = q_meas_;
  out.qd = vel_.estimate();
  out.t = t_sample_;
}

void SimulatedPhantom::write(const VecX& tau) {
  if (tau.size() != caps_.dof) {
    throw InputError("simulated device: torque command has " + std::to_string(tau.size()) +
                     " entries, expected " + std::to_string(caps_.dof));
  }
  faults_ |= condition_command(tau, limits_, cfg_.saturate, tau_applied_);
  if (faults_ != kFaultNone) tau_applied_.setZero();  // latched safe stop
}

double SimulatedPhantom::draw_tick() {
  const TickJitter& j = cfg_.jitter;
  switch (j.kind) {
    case TickJitterKind::kNone:
      return j.period;
    case TickJitterKind::kUniform:
      return std::uniform_real_distribution<double>(j.period - j.half_width,
                                                    j.period + j.half_width)(rng_);
    case TickJitterKind::kNormal:
      return std::normal_distribution<double>(j.period, j.sigma)(rng_);
    case TickJitterKind::kTrace: {
      const double T = j.trace[trace_index_];
      trace_index_ = (trace_index_ + 1) % j.trace.size();
      return T;
    }
  }
  return j.period;
}

void SimulatedPhantom::update_tip_kinematics() {
  const mjModel* m = h_->model();
  mjData* d = h_->data();
  const int b = h_->tip_body_id();
  mj_kinematics(m, d);
  mj_comPos(m, d);
  Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(d->xmat + 9 * b);
  const Eigen::Map<const Vec3> xb(d->xpos + 3 * b);
  tip_.R = R;
  tip_.x = xb + tip_.R * plant_.tip_offset;
  mj_jac(m, d, jacp_.data(), jacr_.data(), tip_.x.data(), b);
}

void SimulatedPhantom::apply_hand(double t) {
  const mjModel* m = h_->model();
  mjData* d = h_->data();
  const int b = h_->tip_body_id();
  update_tip_kinematics();
  const int nv = m->nv;
  Eigen::Map<const RowMat3X> Jp(jacp_.data(), 3, nv);
  Eigen::Map<const RowMat3X> Jr(jacr_.data(), 3, nv);
  Eigen::Map<const VecX> qvel(d->qvel, nv);
  Vec6 V;
  V.head<3>().noalias() = Jp * qvel;  // v (world)
  V_world_.head<3>().noalias() = Jp * qvel;
  V_world_.tail<3>().noalias() = Jr * qvel;
  V.tail<3>().noalias() = tip_.R.transpose() * V_world_.tail<3>();  // w (body)
  F_hand_ = hand_->wrench(tip_, V, t);
  const Vec3 f = F_hand_.head<3>();
  const Vec3 tau_w = tip_.R * F_hand_.tail<3>();  // body -> world
  // xfrc_applied acts at the body's centre of mass (xipos): move the force from the tip point.
  // The human carries the weight of their own hand: a force -m_h g at the tip cancels the
  // gravity on the mass added to the tip body (it is not part of the hand's wrench on the tool).
  const Eigen::Map<const Vec3> gravity(m->opt.gravity);
  const Vec3 f_total = f - hand_->impedance().mass * gravity;
  const Eigen::Map<const Vec3> xipos(d->xipos + 3 * b);
  const Vec3 tau_com = tau_w + (tip_.x - xipos).cross(f_total);
  for (int i = 0; i < 3; ++i) {
    d->xfrc_applied[6 * b + i] = f_total[i];
    d->xfrc_applied[6 * b + 3 + i] = tau_com[i];
  }
  // The hand's joint torques G^T (J_p^T f + J_r^T tau_w).
  Q_tree_.noalias() = Jp.transpose() * f;
  Q_tree_.noalias() += Jr.transpose() * tau_w;
  tau_hand_sub_.noalias() = plant_.G.transpose() * Q_tree_;
}

void SimulatedPhantom::advance() {
  mjModel* m = h_->model();
  mjData* d = h_->data();
  const int n = caps_.dof;
  const double T = draw_tick();
  T_last_ = T;
  if (faults_ != kFaultNone) tau_applied_.setZero();
  // The motors' thermal limit of this tick (derated in place, or a warm-motor fault).
  if (thermal_.active() && thermal_.limit(tau_applied_, T) &&
      cfg_.torque_limit.on_overheat == OnOverheat::kFault) {
    faults_ |= kFaultMotorTemperature;
    tau_applied_.setZero();
  }
  // Zero-order hold: the torque is written once and held over every substep of the tick.
  for (int j = 0; j < m->nv; ++j) d->qfrc_applied[j] = 0.0;
  for (int i = 0; i < n; ++i) d->qfrc_applied[plant_.device_dof[i]] = tau_applied_[i];
  tau_hand_avg_.setZero();
  n_sub_last_ = 0;
  if (T > 0.0) {
    const int N = std::max(1, static_cast<int>(std::ceil(T / cfg_.max_substep - 1e-9)));
    const double h = T / N;
    m->opt.timestep = h;
    for (int s = 0; s < N; ++s) {
      if (hand_ != nullptr) {
        apply_hand(d->time);
        if (s > 0) subtract_hand_inertia(T);
        tau_hand_avg_ += (h / T) * tau_hand_sub_;
        save_hand_substep();
      }
      if (coulomb_tanh_.size() == n) {
        for (int i = 0; i < n; ++i) {
          const int dof = plant_.device_dof[i];
          d->qfrc_applied[dof] =
              tau_applied_[i] - phantom_joint_friction(0.0, coulomb_tanh_[i],
                                                       cfg_.coulomb_velocity[i], d->qvel[dof],
                                                       cfg_.coulomb_sign[static_cast<std::size_t>(i)]);
        }
      }
      mj_step(m, d);
      if (hook_) hook_(d->time, m, d);
    }
    if (hand_ != nullptr) {
      apply_hand(d->time);  // state at the end of the tick closes the last substep
      subtract_hand_inertia(T);
    }
    n_sub_last_ = N;
  }
  thermal_.advance(tau_applied_, T);
  refresh_truth();
  // The device clock: the sum of the drawn tick lengths (a non-positive draw is a clock fault).
  t_prev_sample_ = t_sample_;
  t_sample_ += T;
  q_meas_prev_ = q_meas_;
  sample_encoders();
  faults_ |= check_sample(q_meas_prev_, t_prev_sample_, q_meas_, t_sample_, limits_);
  vel_.update(q_meas_, t_sample_);
  if (faults_ != kFaultNone) tau_applied_.setZero();
  // Tip state (and the hand's wrench) at the sample time.
  if (hand_ != nullptr) {
    if (!(T > 0.0)) apply_hand(d->time);
  } else {
    update_tip_kinematics();
  }
}

void SimulatedPhantom::save_hand_substep() {
  std::copy(jacp_.begin(), jacp_.end(), jacp_prev_.begin());
  std::copy(jacr_.begin(), jacr_.end(), jacr_prev_.begin());
  V_world_prev_ = V_world_;
}

void SimulatedPhantom::subtract_hand_inertia(double T) {
  // The hand's mass moves with the tool: over a substep the hand-tool contact wrench differs from
  // the spring-damper wrench by the hand's momentum change, m_h dv and J_h dw (isotropic J_h about
  // the tip, world frame). Its joint torques, with the Jacobian at the substep start:
  // G^T (J_p^T m_h dv + J_r^T J_h dw) / T, removed from the tick average.
  const int nv = h_->model()->nv;
  Eigen::Map<const RowMat3X> Jp(jacp_prev_.data(), 3, nv);
  Eigen::Map<const RowMat3X> Jr(jacr_prev_.data(), 3, nv);
  const HandImpedance& z = hand_->impedance();
  const Vec3 dp = z.mass * (V_world_.head<3>() - V_world_prev_.head<3>());
  const Vec3 dL = z.inertia * (V_world_.tail<3>() - V_world_prev_.tail<3>());
  Q_tree_.noalias() = Jp.transpose() * dp;
  Q_tree_.noalias() += Jr.transpose() * dL;
  tau_hand_inertia_.noalias() = plant_.G.transpose() * Q_tree_;
  tau_hand_avg_ -= tau_hand_inertia_ / T;
}

void SimulatedPhantom::refresh_truth() {
  const mjModel* m = h_->model();
  const mjData* d = h_->data();
  for (int i = 0; i < caps_.dof; ++i) {
    const int dof = plant_.device_dof[i];
    q_true_[i] = d->qpos[m->jnt_qposadr[m->dof_jntid[dof]]] - plant_.qpos_offset[dof];
    qd_true_[i] = d->qvel[dof];
  }
}

void SimulatedPhantom::sample_encoders() {
  for (int i = 0; i < caps_.dof; ++i) {
    const double dq = caps_.encoder_quantum[i];
    // An incremental encoder counts whole quanta: q = Delta floor(q_true / Delta).
    q_meas_[i] = dq > 0.0 ? dq * std::floor(q_true_[i] / dq) : q_true_[i];
  }
}

Pose SimulatedPhantom::tip_pose() const { return tip_; }

Vec6 SimulatedPhantom::tip_twist() const {
  const mjData* d = h_->data();
  const int nv = h_->model()->nv;
  Eigen::Map<const RowMat3X> Jp(jacp_.data(), 3, nv);
  Eigen::Map<const RowMat3X> Jr(jacr_.data(), 3, nv);
  Eigen::Map<const VecX> qvel(d->qvel, nv);
  Vec6 V;
  V.head<3>() = Jp * qvel;
  V.tail<3>() = tip_.R.transpose() * (Jr * qvel);
  return V;
}

double SimulatedPhantom::energy() const {
  const mjModel* m = h_->model();
  const mjData* d = h_->data();
  mjData* s = scratch_;
  for (int i = 0; i < m->nq; ++i) s->qpos[i] = d->qpos[i];
  for (int i = 0; i < m->nv; ++i) s->qvel[i] = d->qvel[i];
  mj_kinematics(m, s);
  mj_comPos(m, s);
  mj_crb(m, s);
  mj_energyPos(m, s);
  mj_energyVel(m, s);
  return s->energy[0] + s->energy[1];
}

void SimulatedPhantom::set_hand(const ScriptedHand* hand) {
  hand_ = hand;
  merge_hand_mass(hand != nullptr);
  mjData* d = h_->data();
  const int b = h_->tip_body_id();
  for (int i = 0; i < 6; ++i) d->xfrc_applied[6 * b + i] = 0.0;
  tau_hand_avg_.setZero();
  F_hand_.setZero();
  if (hand_ != nullptr) {
    apply_hand(d->time);
  } else {
    update_tip_kinematics();
  }
}

void SimulatedPhantom::merge_hand_mass(bool attach) {
  mjModel* m = h_->model();
  mjData* d = h_->data();
  const int b = h_->tip_body_id();
  double mass = body_mass0_;
  Vec3 ipos(body_ipos0_[0], body_ipos0_[1], body_ipos0_[2]);
  Eigen::Quaterniond iq(body_iquat0_[0], body_iquat0_[1], body_iquat0_[2], body_iquat0_[3]);
  Vec3 inertia(body_inertia0_[0], body_inertia0_[1], body_inertia0_[2]);
  if (attach) {
    // Body + point mass m_h at the tip + isotropic J_h about the tip, in the body frame:
    // c = (m_b c_b + m_h p) / (m_b + m_h), I_c = I_b + m_b (|d_b|^2 I - d_b d_b^T)
    //   + J_h I + m_h (|d_h|^2 I - d_h d_h^T), d_b = c_b - c, d_h = p - c (parallel axes).
    const HandImpedance& z = hand_->impedance();
    const Vec3 p = plant_.tip_offset;
    const double M = body_mass0_ + z.mass;
    const Vec3 c = (body_mass0_ * ipos + z.mass * p) / M;
    const Mat3 Ri = iq.normalized().toRotationMatrix();
    Mat3 I = Ri * inertia.asDiagonal() * Ri.transpose();
    const Vec3 db = ipos - c, dh = p - c;
    I += body_mass0_ * (db.squaredNorm() * Mat3::Identity() - db * db.transpose());
    I += z.mass * (dh.squaredNorm() * Mat3::Identity() - dh * dh.transpose());
    I += z.inertia * Mat3::Identity();
    Eigen::SelfAdjointEigenSolver<Mat3> es(I);
    Mat3 V = es.eigenvectors();
    if (V.determinant() < 0) V.col(2) = -V.col(2);
    mass = M;
    ipos = c;
    iq = Eigen::Quaterniond(V);
    inertia = es.eigenvalues();
  }
  m->body_mass[b] = mass;
  // The compiler's shortcuts for a body whose inertial frame is its frame, or whose mass matrix
  // block is diagonal, no longer hold with the hand: switch them off while it is attached.
  m->body_sameframe[b] = attach ? 0 : body_sameframe0_;
  m->body_simple[b] = attach ? 0 : body_simple0_;
  for (int j = 0; j < m->nv; ++j) {
    if (m->dof_bodyid[j] == b) m->dof_simplenum[j] = attach ? 0 : dof_simplenum0_[j];
  }
  for (int i = 0; i < 3; ++i) {
    m->body_ipos[3 * b + i] = ipos[i];
    m->body_inertia[3 * b + i] = inertia[i];
  }
  m->body_iquat[4 * b + 0] = iq.w();
  m->body_iquat[4 * b + 1] = iq.x();
  m->body_iquat[4 * b + 2] = iq.y();
  m->body_iquat[4 * b + 3] = iq.z();
  // mj_setConst recomputes the derived constants (subtree masses, ...) at qpos0 in d: keep the
  // state and restore it.
  std::vector<double> qpos(d->qpos, d->qpos + m->nq), qvel(d->qvel, d->qvel + m->nv);
  const double time = d->time;
  mj_setConst(m, d);
  for (int i = 0; i < m->nq; ++i) d->qpos[i] = qpos[i];
  for (int i = 0; i < m->nv; ++i) d->qvel[i] = qvel[i];
  d->time = time;
  mj_forward(m, d);
}

}  // namespace dentsim
