#include "reference/tick.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "reference/contact.h"
#include "reference/core/io.h"
#include "reference/coupling.h"
#include "reference/decomposition.h"
#include "reference/encoder_kalman.h"
#include "reference/explicit_euler.h"
#include "reference/friction.h"
#include "reference/grip_detector.h"
#include "reference/lag_compensation.h"
#include "reference/observer.h"
#include "reference/pmi.h"
#include "reference/saturation_passive.h"
#include "reference/tick_detail.h"

namespace dentsim {

PipelineModel make_pipeline_model(const SixDofDeviceModel& device, const PipelineConfig& config) {
  const int n = device.dof();
  PipelineModel m;
  m.device = &device;
  m.method = config.method;
  m.scheme = config.method == Method::kExplicitVc ? Scheme::kExplicit : Scheme::kMidpoint;
  validate_proxy_params(config.proxy);
  m.proxy = config.proxy;
  validate_coupling_gains(config.coupling);
  m.coupling = config.coupling;
  if (!std::isfinite(config.friction.mu) || config.friction.mu < 0.0) {
    throw InputError("friction.mu = " + std::to_string(config.friction.mu) +
                     " (expected a finite coefficient >= 0)");
  }
  m.friction = config.friction;
  m.tool = config.tool;
  m.tool_diagonal = config.tool.M_d.isDiagonal(0.0) && config.tool.D_d.isDiagonal(0.0);
  if (config.method == Method::kPmiPd) {
    m.tool_Md_llt.compute(config.tool.M_d);
    if (m.tool_Md_llt.info() != Eigen::Success || !config.tool.M_d.allFinite()) {
      throw std::invalid_argument("tool '" + config.tool.name +
                                  "' has an M_d that is not positive definite");
    }
    if (!config.tool.D_d.allFinite()) {
      throw std::invalid_argument("tool '" + config.tool.name + "' has a D_d that is not finite");
    }
  }
  if (config.observer_gain.size() != 0) {
    if (config.observer_gain.size() != n) {
      throw std::invalid_argument("observer gain has " +
                                  std::to_string(config.observer_gain.size()) +
                                  " entries; the device has " + std::to_string(n) + " joints");
    }
    validate_observer(config.observer_gain, n, config.observer_input);
    m.observe = true;
    m.observer_gain = config.observer_gain;
    m.observer_input = config.observer_input;
    if (config.grasp_model != nullptr) {
      if (&config.grasp_model->base() != &device) {
        throw std::invalid_argument(
            "grasp_model: its base model must be the pipeline's device model");
      }
      validate_grip_detector(config.grasp_model->mass(), config.grasp_model->inertia(),
                             config.grip_detector);
      m.grasp = true;
      m.grasp_mass.mass = config.grasp_model->mass();
      m.grasp_mass.inertia = config.grasp_model->inertia();
      m.grasp_mass.Mt = config.grasp_model->hand_inertia().diagonal();
      m.grip = config.grip_detector;
      m.grip_norm << Vec3::Constant(1.0 / m.grasp_mass.mass), Vec3::Zero();
    }
  } else if (config.method == Method::kPmiPd) {
    throw std::invalid_argument("method pmi-pd needs the observer gain L (one per joint)");
  }
  if (config.torque_limit.size() != 0) {
    if (config.torque_limit.size() != n) {
      throw std::invalid_argument("torque limit has " + std::to_string(config.torque_limit.size()) +
                                  " entries; the device has " + std::to_string(n) + " joints");
    }
    for (int i = 0; i < n; ++i) {
      if (!(config.torque_limit(i) >= 0.0) || std::isnan(config.torque_limit(i))) {
        throw std::invalid_argument("torque limit[" + std::to_string(i) +
                                    "] = " + std::to_string(config.torque_limit(i)) +
                                    " N m (expected >= 0)");
      }
    }
    m.saturate = true;
    m.torque_limit = config.torque_limit;
  }
  m.compensate_gravity = config.compensate_gravity;
  if (config.encoder_kalman) {
    if (config.encoder_quantum.size() != 0 && config.encoder_quantum.size() != n) {
      throw std::invalid_argument("encoder quantum has " +
                                  std::to_string(config.encoder_quantum.size()) +
                                  " entries; the device has " + std::to_string(n) + " joints");
    }
    for (int i = 0; i < config.encoder_quantum.size(); ++i) {
      if (!(config.encoder_quantum(i) >= 0.0) || !std::isfinite(config.encoder_quantum(i))) {
        throw std::invalid_argument("encoder quantum[" + std::to_string(i) + "] = " +
                                    std::to_string(config.encoder_quantum(i)) +
                                    " (expected finite and >= 0)");
      }
    }
    const EncoderKalmanParams& ek = config.encoder_kalman_params;
    if (!(ek.force_sigma_n > 0.0) || !std::isfinite(ek.force_sigma_n) ||
        !(ek.grip_lever_m >= 0.0) || !std::isfinite(ek.grip_lever_m)) {
      throw std::invalid_argument(
          "encoder Kalman filter: force_sigma_n must be > 0 and grip_lever_m >= 0, both finite");
    }
    m.encoder_kalman = true;
    if (config.encoder_quantum.size() == n) m.encoder_quantum = config.encoder_quantum;
    m.encoder_kalman_params = ek;
    if (ek.model_friction && ek.stick_slip) {
      Vec6 b = Vec6::Zero(), f_c = Vec6::Zero();
      if (!device.joint_friction_coefficients(&b, &f_c)) {
        throw std::invalid_argument(
            "encoder Kalman filter: the stick-slip friction model needs the device model's "
            "viscous and Coulomb coefficients, and this device model does not give them");
      }
      if (!b.allFinite() || !f_c.allFinite() || (b.array() < 0.0).any() ||
          (f_c.array() < 0.0).any()) {
        throw std::invalid_argument(
            "encoder Kalman filter: the device model's friction coefficients must be finite and "
            ">= 0 for the stick-slip friction model");
      }
      m.encoder_friction_b = b;
      m.encoder_friction_fc = f_c;
    }
    // The filter's velocity carries no driver low-pass and is no backward difference: the
    // observer takes the torque as it was applied (reference/observer.h, unmatched input).
    m.observer_input = ObserverInput{};
  }
  m.lag_compensation = config.lag_compensation;
  if (config.lag_compensation) {
    if (!(config.velocity_estimate.lowpass_hz >= 0.0) ||
        !std::isfinite(config.velocity_estimate.lowpass_hz)) {
      throw std::invalid_argument("lag compensation: velocity_estimate.lowpass_hz = " +
                                  std::to_string(config.velocity_estimate.lowpass_hz) +
                                  " (expected finite and >= 0)");
    }
    // The encoder Kalman filter's estimate replaces the driver's: it has no difference or
    // low-pass lag (reference/encoder_kalman.h).
    m.velocity_estimate = config.encoder_kalman ? ObserverInput{} : config.velocity_estimate;
  }
  // Without limits nothing saturates: the shape control has nothing to do. Nor under explicit
  // Euler: it has no feed-forward, and its coupling is integrated explicitly, where capping the
  // spring does not make the step passive (its stability is the load-time check's and the
  // supervisor's); the control is for PMI's implicit step (pmi, pmi-pd).
  m.saturation_passive =
      config.saturation_passive && m.saturate && config.method != Method::kExplicitVc;
  m.skip_unneeded = config.skip_unneeded;
  m.time_stages = config.time_stages;
  if (!m.skip_unneeded && config.method != Method::kPmiPd) {
    // The decomposition runs (and is discarded) with skips off: it needs M_d factorised.
    m.tool_Md_llt.compute(config.tool.M_d);
  }
  return m;
}

namespace reference {

namespace {

// The device model's joint acceleration under the torque applied over the tick that ended and the
// observer's estimate of the hand, a = M^-1 (tau_prev + f_hat - g - tau_f), with the terms `t`,
// the hypothesis in force of the grip detector and its inertia M (model_joint_inertia; Coriolis
// neglected at haptic speeds); without the model's friction tau_f unless `with_friction`. Zero if
// M is not SPD or a is not finite. Used by the encoder Kalman filter's prediction and the
// loop-lag compensation.
// The joint torque the device model knows apart from friction: tau_prev + f_hat - g (the torque
// applied over the tick that ended, the observer's estimate under the hypothesis in force).
Vec6 model_joint_torque(const PipelineModel& m, const PipelineData& d, const DeviceTerms& t) {
  const bool gripped = m.grasp && d.grip.gripped;
  Vec6 f_hat = Vec6::Zero();
  if (m.observe) f_hat = gripped ? d.obs1.f_hat : d.obs0.f_hat;
  return d.tau_prev + f_hat - t.g;
}

Vec6 model_joint_acceleration(const PipelineModel& m, const PipelineData& d, const DeviceTerms& t,
                              const Mat6& M, bool with_friction, detail::SolveInertia solve) {
  Vec6 accel = Vec6::Zero();
  Vec6 b = model_joint_torque(m, d, t);
  if (with_friction) b -= t.tau_f;
  if (!solve(M, b, &accel) || !accel.allFinite()) accel.setZero();
  return accel;
}

// The encoder Kalman filter's step (reference/encoder_kalman.h): predicts with the model terms of
// the tick that just ended (d.dev, the hypothesis in force, the torque applied over it and the
// observer's estimate), corrects with the sample, and puts the estimate in d.q, d.qd.
void encoder_kalman_step(const PipelineModel& m, PipelineData& d, detail::SolveInertia solve) {
  if (!d.enc.ready) {
    encoder_kalman_reset(d.q, d.qd, m.encoder_quantum, d.enc);
  } else {
    const double T = d.have_prev && d.t > d.t_prev ? d.t - d.t_prev : d.T;
    const DeviceTerms& t = d.dev;
    const Mat6 M = detail::model_joint_inertia(m, d, t.M);
    // sigma_a,i = sigma_f (|J_v,i| + lever |J_w,i|) / M_ii: the force the model does not know.
    const EncoderKalmanParams& p = m.encoder_kalman_params;
    Vec6 sigma_a = Vec6::Zero();
    for (int i = 0; i < 6; ++i) {
      const double lever =
          t.J_t.col(i).head<3>().norm() + p.grip_lever_m * t.J_t.col(i).tail<3>().norm();
      sigma_a(i) = M(i, i) > 0.0 ? p.force_sigma_n * lever / M(i, i) : 0.0;
    }
    // model_friction false: the prediction leaves the joints' friction to the process noise (a
    // haptic standstill's Coulomb friction is set-valued; the model's smooth f_c tanh(qd / v_s)
    // at the filter's own velocity closes a velocity loop inside the filter that M^-1 carries
    // from the arm into the gimbal: docs/derivations/quiet_stiffness.md 8.6).
    Vec6 accel = Vec6::Zero();
    Vec6 v_plus = Vec6::Zero();
    if (p.model_friction && p.stick_slip &&
        encoder_stick_slip_velocity(M, m.encoder_friction_b, m.encoder_friction_fc, d.enc.qd,
                                    model_joint_torque(m, d, t), T, &v_plus)) {
      // Set-valued friction (8.7): the joints that stick predict no motion at all.
      accel = (v_plus - d.enc.qd) / T;
    } else {
      accel = model_joint_acceleration(m, d, t, M, p.model_friction, solve);
    }
    encoder_kalman_update(d.q, d.qd, m.encoder_quantum, accel, sigma_a, T, d.enc);
  }
  d.q = d.enc.q;
  d.qd = d.enc.qd;
}

// The saturation-passive shape control's cap (reference/saturation_passive.h), engaged: the
// coupling's linear spring (d.coupling, r.T1_vc) limited to the force the device delivers along it.
void cap_coupling_to_device(const PipelineModel& m, PipelineData& d) {
  TickResult& r = d.r;
  const Vec3 e = d.proxy.pose.x - r.device.x;
  const double stretch = e.norm();
  if (!(stretch > 0.0)) return;
  const Vec6 tau_gravity = m.compensate_gravity ? d.dev.g : Vec6::Zero();
  const double cap =
      deliverable_force(d.dev.J_t, m.torque_limit, tau_gravity, e / stretch, kSaturationHeadroom);
  r.coupling_force_cap = cap;
  d.coupling_capped =
      cap_coupling_spring(m.coupling.k_lin, r.device.x, d.proxy.pose.x, cap, &d.coupling, &r.T1_vc);
}

// The saturation-passive shape control's state after this tick's command (unsaturated `tau`, the
// decomposition's feed-forward at its full scale): engages on a saturated command; sigma the
// largest feed-forward scale the limits allow, raised at most T / kShapeSigmaRecoveryS a tick;
// released once sigma is back at 1 and the cap does not bind.
void update_shape_control(const PipelineModel& m, PipelineData& d, const Vec6& tau) {
  TickResult& r = d.r;
  if (!d.shape_engaged && !r.saturated) return;
  Vec6 b = Vec6::Zero();
  if (m.method == Method::kPmiPd) {
    // The feed-forward at full scale, pd_T1 at V_hat: the solve's r.T1_pd itself unless the
    // control was engaged there (solve_with scaled it by sigma then).
    const Vec6 T1_pd = d.shape_engaged ? pd_T1_at(d, r.V_hat) : r.T1_pd;
    b.noalias() = d.dev.J_t.transpose() * T1_pd;
  }
  const Vec6 a = tau - d.shape_sigma * b;  // the command without the feed-forward
  const double feasible = feasible_feedforward_scale(a, b, m.torque_limit, kSaturationHeadroom);
  d.shape_sigma = std::min(feasible, d.shape_sigma + d.T / kShapeSigmaRecoveryS);
  d.shape_engaged = d.shape_sigma < 1.0 || d.coupling_capped || r.saturated;
  if (!d.shape_engaged) d.shape_sigma = 1.0;
}

}  // namespace

namespace {

void invert_jacobian(const PipelineModel&, const Mat6& J_t, PipelineData& d) {
  d.J_t_lu.compute(J_t);
  d.J1 = d.J_t_lu.inverse();
}

bool solve_inertia(const Mat6& M, const Vec6& b, Vec6* x) {
  const Eigen::LLT<Mat6> llt(M);
  if (llt.info() != Eigen::Success) return false;
  *x = llt.solve(b);
  return true;
}

}  // namespace

TickStatus device_terms(const PipelineModel& m, PipelineData& d) {
  return detail::device_terms_with(m, d, invert_jacobian, solve_inertia);
}

TickStatus detail::device_terms_with(const PipelineModel& m, PipelineData& d,
                                     InvertJacobian invert, SolveInertia solve) {
  if (m.encoder_kalman) encoder_kalman_step(m, d, solve);
  // One pass of the device model: x1, R1, J_t (V1 = J_t qd), M, C^T qd, g, tau_f   (2.1), (2.2)
  DeviceTerms& t = d.dev;
  m.device->terms(d.q, d.qd, m.grasp, t);
  if (!all_finite(t.pose.x, t.pose.R, t.J_t, t.J_t_dot, t.M, t.CTqd, t.g, t.tau_f)) {
    return TickStatus::kDeviceModelFailure;
  }
  // J1 = J_t^-1 (2.2): the one inverse a tick needs (observer wrench, device inertia).
  invert(m, t.J_t, d);
  if (!all_finite(d.J1)) return TickStatus::kDeviceModelFailure;
  d.r.device = t.pose;
  d.r.V1.noalias() = t.J_t * d.qd;  // V1 = J_t qd                                   (2.2)
  if (m.grasp) grasp_mass_terms(m.grasp_mass.Mt, t, d.r.V1, &d.M_hand, &d.CTqd_hand);
  if (m.lag_compensation && d.have_prev) {
    // Loop-lag compensation (reference/lag_compensation.h): the coupling and D_d see the velocity
    // at the midpoint of the coming tick; the observer and the hand's terms keep the measured one.
    const double T_last = d.t > d.t_prev ? d.t - d.t_prev : d.T;
    const Vec6 accel =
        model_joint_acceleration(m, d, t, detail::model_joint_inertia(m, d, t.M), true, solve);
    d.r.V1.noalias() = t.J_t * (d.qd + loop_velocity_lag(m.velocity_estimate, T_last, d.T) * accel);
  }
  return TickStatus::kOk;
}

TickStatus observe(const PipelineModel& m, PipelineData& d) {
  return detail::observe_with(
      m, d, [](const PipelineModel& mm, PipelineData& dd, const Vec6& h0, const Vec6& h1) {
        return grip_filter_update(mm.grip, mm.grip_norm, dd.grip, h0, h1, dd.T_last);
      });
}

TickStatus detail::observe_with(const PipelineModel& m, PipelineData& d, GripUpdate grip) {
  // Observer (3.7)-(3.8): joint estimate from the torque applied over the last tick, which
  // lasted from the previous sample to this one (tick lengths may vary).
  TickResult& r = d.r;
  r.F1_hat.setZero();
  r.grip_state = -1;
  d.T_last = d.have_prev && d.t > d.t_prev ? d.t - d.t_prev : d.T;
  d.t_prev = d.t;
  d.have_prev = true;
  if (!m.observe) return TickStatus::kOk;
  const DeviceTerms& t = d.dev;
  // beta = C^T qd - g - tau_f (3.7), p = M qd
  const Vec6 beta = t.CTqd - t.g - t.tau_f;
  const Vec6 Mqd = t.M * d.qd;
  momentum_observer_update<Vec6>(m.observer_gain, m.observer_input, d.obs0, Mqd, beta, d.tau_prev,
                                 d.T_last);
  if (!m.grasp) {
    r.F1_hat.noalias() = d.J1.transpose() * d.obs0.f_hat;  // F1 = J1^T f1
    return TickStatus::kOk;
  }
  // Grip detector: the second hypothesis adds the hand's mass, M' = M + M_h, C'^T qd = C^T qd +
  // C_h^T qd (reference/grasp_mass_model.h).
  const Vec6 beta1 = beta + d.CTqd_hand;
  const Vec6 Mqd1 = Mqd + d.M_hand * d.qd;
  momentum_observer_update<Vec6>(m.observer_gain, m.observer_input, d.obs1, Mqd1, beta1, d.tau_prev,
                                 d.T_last);
  const Vec6 h0 = d.J1.transpose() * d.obs0.f_hat;
  const Vec6 h1 = d.J1.transpose() * d.obs1.f_hat;
  const bool gripped = grip(m, d, h0, h1);
  r.grip_state = gripped ? 1 : 0;
  r.grip_statistic = d.grip.p1 - d.grip.p0;
  r.F1_hat = gripped ? h1 : h0;
  return TickStatus::kOk;
}

TickStatus collide(const PipelineModel&, PipelineData& d) {
  TickResult& r = d.r;
  if (!d.env->contacts(d.proxy.pose, r.contacts)) return TickStatus::kContactBufferFull;
  if (!contacts_well_formed(r.contacts)) return TickStatus::kBadContact;
  r.max_depth = 0.0;
  for (const Contact& c : r.contacts) {
    r.max_depth = std::max(r.max_depth, penetration_depth(c, d.proxy.pose));
  }
  return TickStatus::kOk;
}

TickStatus assemble(const PipelineModel& m, PipelineData& d) {
  d.contact = contact_wrench_unchecked(d.r.contacts, d.proxy.pose, d.T, m.scheme);
  if (const AnchoredSpring* a = anchored_spring(d.env)) {  // the surface proxy (issue #32)
    add_anchored_spring_unchecked(&d.contact, d.r.contacts, d.proxy.pose, d.T, m.scheme, *a,
                                  m.coupling.b_lin + m.proxy.damping_lin,
                                  m.coupling.b_ang + m.proxy.damping_ang);
  }
  return detail::assemble_given_contact(m, d);
}

namespace detail {

TickStatus assemble_given_contact(const PipelineModel& m, PipelineData& d) {
  return assemble_given_contact_with(m, d, pd_step);
}

bool pd_step(const PipelineModel& m, PipelineData& d) {
  const TickResult& r = d.r;
  // The device inertia in maximal coordinates (2.2) under the hypothesis in force.
  const Mat6 M_joint = model_joint_inertia(m, d, d.dev.M);
  const Mat6 M1 = d.J1.transpose() * M_joint * d.J1;
  Decomposition dec;
  if (!decompose_locked(M1, m.proxy.M(), r.device.R, d.proxy.pose.R, &dec)) return false;
  const PdFeedforward pd =
      pd_feedforward(dec, m.tool_Md_llt, m.tool.D_d, r.V1, r.F1_hat, d.contact);  // (4.7)
  d.pd_T1 = pd.T1;
  d.pd_T2 = pd.T2;
  return true;
}

TickStatus assemble_given_contact_with(const PipelineModel& m, PipelineData& d, PdStep pd) {
  // Force elements on the proxy, affine in the velocity they are evaluated at (the contact's,
  // d.contact, already there).
  TickResult& r = d.r;
  d.coupling = coupling_proxy_wrench_unchecked(m.coupling, r.device, r.V1, d.proxy, d.T, m.scheme);
  // Device-side coupling (4.3)-(4.4): uses the proxy at k and V_hat_2,k-1.
  r.T1_vc = coupling_device_wrench_unchecked(m.coupling, r.device, r.V1, d.proxy, d.T, m.scheme);
  // Saturation-passive shape control (reference/saturation_passive.h): engaged only after a
  // saturated command; otherwise nothing below is touched.
  const bool shaped = m.saturation_passive && d.shape_engaged;
  r.shape_sigma = 1.0;
  r.coupling_force_cap = 0.0;
  d.coupling_capped = false;
  if (shaped) {
    cap_coupling_to_device(m, d);
    r.shape_sigma = d.shape_sigma;
  }
  if (m.method == Method::kPmiPd && !pd(m, d)) return TickStatus::kDeviceModelFailure;
  if (m.method != Method::kExplicitVc) {
    // PMI (4.9): inertia, coupling, contact and the feed-forward in one 6x6 system.
    d.sys = pmi_inertia_system_unchecked(m.proxy, d.proxy, d.T);
    d.sys.add(d.coupling);
    d.sys.add(d.contact);
    if (m.method == Method::kPmiPd) {
      if (shaped) {
        AffineWrench T2 = d.pd_T2;  // the proxy's share scaled by sigma with the device's
        T2.f0 *= d.shape_sigma;
        T2.G *= d.shape_sigma;
        d.sys.add(T2);
      } else {
        d.sys.add(d.pd_T2);
      }
    }
  }
  return TickStatus::kOk;
}

}  // namespace detail

TickStatus solve(const PipelineModel& m, PipelineData& d) {
  return detail::solve_with(m, d, pmi_try_solve, solve_with_friction_unchecked, m.friction);
}

namespace detail {

TickStatus solve_with(const PipelineModel& m, PipelineData& d,
                      bool (*pmi_solver)(const PmiSystem&, Vec6*), FrictionSolve friction_solver,
                      const FrictionParams& friction, bool even_without_contacts) {
  TickResult& r = d.r;
  r.friction_sliding = false;
  if (m.method == Method::kExplicitVc) {
    // Explicit Euler: every force at V_k.
    r.V_hat = d.proxy.V;
    r.F_coupling = d.coupling.at(d.proxy.V);
    r.F_contact = d.contact.at(d.proxy.V);
    r.T1_pd.setZero();
    const Vec6 F = r.F_coupling + r.F_contact;
    if (!F.allFinite()) return TickStatus::kSolverFailure;
    d.proxy = explicit_euler_advance_unchecked(m.proxy, d.proxy, F, d.T);
    return TickStatus::kOk;
  }
  // PMI (4.9): one linear solve for V_hat, friction as tangential multipliers (2.21)-(2.22).
  Vec6 friction_wrench = Vec6::Zero();
  if (friction.enabled && (!r.contacts.empty() || even_without_contacts)) {
    FrictionSolution fs;
    if (!friction_solver(d.sys, r.contacts, d.proxy.pose, d.contact, friction, &fs)) {
      return TickStatus::kSolverFailure;
    }
    r.V_hat = fs.V;
    r.friction_sliding = fs.sliding;
    friction_wrench = fs.F;  // (4.10)
  } else if (!pmi_solver(d.sys, &r.V_hat)) {
    return TickStatus::kSolverFailure;
  }
  r.F_coupling = d.coupling.at(r.V_hat);
  r.F_contact = d.contact.at(r.V_hat) + friction_wrench;
  r.T1_pd = m.method == Method::kPmiPd ? pd_T1_at(d, r.V_hat) : Vec6::Zero();
  if (m.saturation_passive && d.shape_engaged) r.T1_pd *= d.shape_sigma;  // (saturation_passive.h)
  d.proxy = pmi_advance_unchecked(d.proxy, r.V_hat, d.T);
  return TickStatus::kOk;
}

}  // namespace detail

TickStatus command(const PipelineModel& m, PipelineData& d) {
  // Device command: tau1 = J_t^T T1 + g(q), scaled down uniformly (direction kept) to the limits.
  TickResult& r = d.r;
  r.T1 = r.T1_vc + r.T1_pd;
  Vec6 tau = d.dev.J_t.transpose() * r.T1;  // qd^T tau1 = V1^T T1 with V1 = J_t qd   (2.2)
  Vec6 tau_gravity = Vec6::Zero();
  if (m.compensate_gravity) {
    tau_gravity = d.dev.g;  // (2.1): gravity compensated
    tau += tau_gravity;
  }
  r.saturated = false;
  const Vec6 tau_unsaturated = tau;
  if (m.saturate) {
    double scale = 1.0;
    for (int i = 0; i < 6; ++i) {
      const double a = std::abs(tau(i));
      if (a > m.torque_limit(i)) scale = std::min(scale, m.torque_limit(i) / a);
    }
    if (scale < 1.0) {
      tau *= scale;
      tau_gravity *= scale;
      r.saturated = true;
    }
  }
  if (!tau.allFinite() || !d.proxy.pose.x.allFinite() || !d.proxy.pose.R.allFinite() ||
      !d.proxy.V.allFinite()) {
    return TickStatus::kNonFiniteOutput;
  }
  if (m.saturation_passive) update_shape_control(m, d, tau_unsaturated);
  r.tau = tau;
  r.tau_gravity = tau_gravity;
  d.tau_prev = tau;
  return TickStatus::kOk;
}

TickStatus drill(const PipelineModel&, PipelineData& d) {
  TickResult& r = d.r;
  r.removed_voxels = 0;
  if (d.env->drills() && !r.contacts.empty()) r.removed_voxels = d.env->drill(r.contacts, d.T);
  if (d.env->drill_store_full()) return TickStatus::kDrillWorkTableFull;
  // The collide stage's edit and this stage's queue (tooth_contacts.h): both counted by now.
  if (d.env->field_edit_shortfall()) return TickStatus::kFieldEditShortfall;
  return TickStatus::kOk;
}

TickStatus reset(const PipelineModel& m, PipelineData& d) {
  d.enc.ready = false;
  const TickStatus st = device_terms(m, d);
  if (st != TickStatus::kOk) return st;
  d.proxy = ProxyState{};
  d.proxy.pose = d.dev.pose;
  d.tau_prev.setZero();
  d.shape_sigma = 1.0;
  d.shape_engaged = false;
  d.coupling_capped = false;
  if (m.observe) {
    const Vec6 beta = d.dev.CTqd - d.dev.g - d.dev.tau_f;
    const Vec6 Mqd = d.dev.M * d.qd;
    momentum_observer_reset<Vec6>(d.obs0, Mqd, beta);
    if (m.grasp) {
      momentum_observer_reset<Vec6>(d.obs1, Vec6(Mqd + d.M_hand * d.qd), Vec6(beta + d.CTqd_hand));
      grip_filter_reset(m.grip, d.grip);
    }
  }
  return TickStatus::kOk;
}

}  // namespace reference

const StageTable& reference_stage_table() {
  static const StageTable kTable = {
      "reference",
      {reference::device_terms, reference::observe, reference::collide, reference::assemble,
       reference::solve, reference::command, reference::drill},
      reference::reset};
  return kTable;
}

StagedPipeline::StagedPipeline(const StageTable& table, const SixDofDeviceModel& device,
                               const PipelineConfig& config)
    : table_(&table),
      model_(make_pipeline_model(device, config)),
      data_(std::make_unique<PipelineData>()) {}

TickStatus StagedPipeline::reset(const DeviceSample& s) {
  return pipeline_reset(*table_, model_, *data_, s);
}

const TickResult& StagedPipeline::tick(const DeviceSample& s, double T, ContactProvider& contacts) {
  pipeline_tick(*table_, model_, *data_, s, T, contacts);
  return data_->r;
}

}  // namespace dentsim
