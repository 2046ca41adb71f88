#include "fast/tick.h"

#include <limits>
#include <typeinfo>

#include "fast/contact.h"
#include "fast/coupling.h"
#include "fast/decomposition.h"
#include "fast/dense6.h"
#include "fast/encoder_kalman.h"
#include "fast/friction.h"
#include "fast/grasp_mass_model.h"
#include "fast/phantom/phantom_model.h"
#include "fast/pmi.h"
#include "reference/decomposition.h"
#include "reference/encoder_kalman.h"
#include "reference/grip_detector.h"
#include "reference/observer.h"
#include "reference/pmi.h"
#include "reference/tick_detail.h"

namespace dentsim::fast {

namespace {

// Skips off (PipelineModel::skip_unneeded false): the work a skip saves, run and then discarded,
// so that tests/fast/skip_test.cc can check that skipping changes nothing and
// bench/skip_bench.cc can measure what each skip saves.

// The observers and the grip detector the scene does not model: with no observer gain both
// observers run at gain zero (their estimate stays zero); with no hand mass the second hypothesis
// is the first (M_h = 0), so its estimate equals the first's and the detector's choice does not
// matter. F1_hat is what the reference stage computed either way.
void unneeded_observers(const PipelineModel& m, PipelineData& d) {
  const DeviceTerms& t = d.dev;
  const Vec6 beta = t.CTqd - t.g - t.tau_f;
  const Vec6 Mqd = t.M * d.qd;
  if (!m.observe) {
    momentum_observer_update<Vec6>(Vec6::Zero(), m.observer_input, d.obs0, Mqd, beta, d.tau_prev,
                                   d.T_last);
  }
  const Vec6 L = m.observe ? m.observer_gain : Vec6::Zero();
  momentum_observer_update<Vec6>(L, m.observer_input, d.obs1, Mqd, beta, d.tau_prev, d.T_last);
  const Vec6 h0 = d.J1.transpose() * d.obs0.f_hat;
  const Vec6 h1 = d.J1.transpose() * d.obs1.f_hat;
  const bool gripped = grip_filter_update(m.grip, m.grip_norm, d.grip, h0, h1, d.T_last);
  d.r.F1_hat = gripped ? h1 : h0;
}

// The decomposition and feed-forward (4.7) a method other than pmi-pd does not use: computed into
// d.pd_T1 / d.pd_T2, which such a method never reads.
void unneeded_decomposition(const PipelineModel& m, PipelineData& d) {
  if (m.tool_Md_llt.info() != Eigen::Success) return;
  const Mat6 M1 = d.J1.transpose() * d.dev.M * d.J1;
  Decomposition dec;
  if (!decompose_locked(M1, m.proxy.M(), d.r.device.R, d.proxy.pose.R, &dec)) return;
  const PdFeedforward pd =
      pd_feedforward(dec, m.tool_Md_llt, m.tool.D_d, d.r.V1, d.r.F1_hat, d.contact);
  d.pd_T1 = pd.T1;
  d.pd_T2 = pd.T2;
}

// The decomposition's feed-forward on its block structure (fast/decomposition.h) when M_d and
// D_d are diagonal (PipelineModel::tool_diagonal, decided at setup); the reference's step
// otherwise. T1 is kept factored (PipelineData::pd_T1_factored): the tick reads it at V_hat only.
bool pd_step(const PipelineModel& m, PipelineData& d) {
  d.pd_T1_factored = false;
  if (!m.tool_diagonal) return reference::detail::pd_step(m, d);
  const TickResult& r = d.r;
  // M1 = J1^T M J1 (2.2), M under the hypothesis in force (model_joint_inertia): with the hand on
  // the tool, J1^T (M + J_t^T Mt J_t) J1 = J1^T M J1 + Mt (J_t J1 = I), the hand's inertia at the
  // tool without M_hand (the reference's sum differs by round-off, eps cond(J_t) |Mt|).
  Mat6& M1 = d.pd_M1;
  inertia_at_tool(d.J1, d.dev.M, &M1);  // exactly symmetric
  if (m.grasp && d.grip.gripped) M1.diagonal() += m.grasp_mass.Mt;
  // A free tick with skips on: fast::assemble set d.contact to zero (no contact, no spring).
  const FeedforwardKnown known{m.skip_unneeded && r.contacts.empty(), true};
  d.pd_T1_factored =
      pd_feedforward_diagonal_factored(M1, m.proxy, m.tool, r.device.R, d.proxy.pose.R, r.V1,
                                       r.F1_hat, d.contact, &d.pd_W, &d.pd_T2, known);
  return d.pd_T1_factored;
}

// J1 = J_t^-1: on the Phantom's block structure when the device is fast::PhantomModel and its
// gimbal's joints meet at a point (fast/phantom/phantom_model.h section 6), by fast/dense6.h's LU
// otherwise; a singular J_t leaves a non-finite J1, which the stage reports as the reference's does.
void invert_jacobian(const PipelineModel& m, const Mat6& J_t, PipelineData& d) {
  const SixDofDeviceModel& device = *m.device;
  if (typeid(device) == typeid(PhantomModel) &&
      static_cast<const PhantomModel&>(device).jacobian_inverse(J_t, d.dev.pose.R, &d.J1)) {
    return;
  }
  Lu6 lu;
  if (!lu6(J_t, &lu)) {
    d.J1.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  lu6_inverse(lu, &d.J1);
}

// x = M^-1 b by fast/dense6.h's Cholesky (the model acceleration of the encoder Kalman filter and
// the loop-lag compensation).
bool solve_inertia(const Mat6& M, const Vec6& b, Vec6* x) {
  Llt6 llt;
  if (!cholesky6(M, &llt)) return false;
  cholesky6_solve(llt, b, x);
  return true;
}

// The encoder Kalman filter's step of reference/tick.cc (encoder_kalman_step) without its
// copies: M is the device's own inertia, read in place, unless the hand's hypothesis adds M_hand
// (then M + M_hand, the reference's sum); the model acceleration a = M^-1 (tau_prev + f_hat - g -
// tau_f) by fast/dense6.h's Cholesky and the correction by fast/encoder_kalman.h, each the same
// operations on the same doubles. With the stick-slip friction model the reference's stage runs
// instead (device_terms below).
void encoder_kalman_step(const PipelineModel& m, PipelineData& d) {
  if (!d.enc.ready) {
    encoder_kalman_reset(d.q, d.qd, m.encoder_quantum, d.enc);
  } else {
    const double T = d.have_prev && d.t > d.t_prev ? d.t - d.t_prev : d.T;
    const DeviceTerms& t = d.dev;
    const bool gripped = m.grasp && d.grip.gripped;
    Mat6 M_gripped;
    if (gripped) M_gripped.noalias() = t.M + d.M_hand;
    const Mat6& M = gripped ? M_gripped : t.M;
    // sigma_a,i = sigma_f (|J_v,i| + lever |J_w,i|) / M_ii (fast/encoder_kalman.h)
    const EncoderKalmanParams& p = m.encoder_kalman_params;
    Vec6 sigma_a;
    encoder_acceleration_noise(t.J_t, M, p, &sigma_a);
    const Vec6 f_hat = !m.observe ? Vec6::Zero() : gripped ? d.obs1.f_hat : d.obs0.f_hat;
    Vec6 b = d.tau_prev + f_hat - t.g;
    if (p.model_friction) b -= t.tau_f;
    Vec6 accel;
    if (!solve_inertia(M, b, &accel) || !reference::detail::all_finite(accel)) accel.setZero();
    fast::encoder_kalman_update(d.q, d.qd, m.encoder_quantum, accel, sigma_a, T, d.enc);
  }
  d.q = d.enc.q;
  d.qd = d.enc.qd;
}

// reference/tick.cc's assemble_given_contact_with(m, d, pd_step), line for line, with both
// coupling wrenches from fast/coupling.h (bitwise the reference's two calls). While the
// saturation-passive shape control is engaged (after a saturated command) the reference's stage
// runs, with the same pd_step.
TickStatus assemble_given_contact(const PipelineModel& m, PipelineData& d) {
  if (m.saturation_passive && d.shape_engaged) {
    return reference::detail::assemble_given_contact_with(m, d, pd_step);
  }
  TickResult& r = d.r;
  coupling_wrenches_unchecked(m.coupling, r.device, r.V1, d.proxy, d.T, m.scheme, &d.coupling,
                              &r.T1_vc);
  r.shape_sigma = 1.0;
  r.coupling_force_cap = 0.0;
  d.coupling_capped = false;
  if (m.method == Method::kPmiPd && !pd_step(m, d)) return TickStatus::kDeviceModelFailure;
  if (m.method != Method::kExplicitVc) {
    // PMI (4.9): inertia, coupling, contact and the feed-forward in one 6x6 system.
    d.sys = pmi_inertia_system_unchecked(m.proxy, d.proxy, d.T);
    d.sys.add(d.coupling);
    d.sys.add(d.contact);
    if (m.method == Method::kPmiPd) d.sys.add(d.pd_T2);
  }
  return TickStatus::kOk;
}

}  // namespace

// The device model does the work (fast::PhantomModel with the fast pipeline); J1 = J_t^-1, the
// inertia's solve and the encoder Kalman filter are fast/ kernels (above); the stage around them
// is reference/tick.cc's device_terms_with, line for line. The loop-lag compensation and the
// stick-slip friction model of the encoder filter take the reference's stage (with the same
// kernels).
TickStatus device_terms(const PipelineModel& m, PipelineData& d) {
  if (m.lag_compensation ||
      (m.encoder_kalman && m.encoder_kalman_params.model_friction &&
       m.encoder_kalman_params.stick_slip)) {
    return reference::detail::device_terms_with(m, d, invert_jacobian, solve_inertia);
  }
  if (m.encoder_kalman) encoder_kalman_step(m, d);
  // One pass of the device model: x1, R1, J_t (V1 = J_t qd), M, C^T qd, g, tau_f   (2.1), (2.2)
  DeviceTerms& t = d.dev;
  m.device->terms(d.q, d.qd, m.grasp, t);
  if (!reference::detail::all_finite(t.pose.x, t.pose.R, t.J_t, t.J_t_dot, t.M, t.CTqd, t.g,
                                     t.tau_f)) {
    return TickStatus::kDeviceModelFailure;
  }
  invert_jacobian(m, t.J_t, d);  // J1 = J_t^-1 (2.2)
  if (!reference::detail::all_finite(d.J1)) return TickStatus::kDeviceModelFailure;
  d.r.device = t.pose;
  d.r.V1.noalias() = t.J_t * d.qd;  // V1 = J_t qd                                   (2.2)
  if (m.grasp) fast::grasp_mass_terms(m.grasp_mass.Mt, t, d.r.V1, &d.M_hand, &d.CTqd_hand);
  return TickStatus::kOk;
}

bool grip_filter_update_kept(const GripDetectorParams& p, const Vec6& norm, GripFilterState& s,
                             GripGainMemo& memo, const Vec6& h0, const Vec6& h1, double T) {
  int i = 0;
  while (i < GripGainMemo::kSize && !(memo.T[i] == T)) ++i;
  if (i == GripGainMemo::kSize) {  // a new T: its gains replace the oldest kept
    i = memo.next;
    memo.next = (i + 1) % GripGainMemo::kSize;
    memo.T[i] = T;
    memo.g[i] = grip_filter_gains(p, T);
  }
  return grip_filter_update(p, norm, s, h0, h1, memo.g[i], T);
}

namespace {

bool grip_update(const PipelineModel& m, PipelineData& d, const Vec6& h0, const Vec6& h1) {
  return grip_filter_update_kept(m.grip, m.grip_norm, d.grip, d.grip_gains, h0, h1, d.T_last);
}

}  // namespace

// Two 6-vector observer updates: already allocation-free and O(36) flops; the reference's stage
// with the grip filter's gains kept by tick length (grip_filter_update_kept, fast/tick.h). Skipped
// (by the reference stage) without an observer gain; the grip detector only with a hand mass.
TickStatus observe(const PipelineModel& m, PipelineData& d) {
  const TickStatus st = reference::detail::observe_with(m, d, grip_update);
  if (st == TickStatus::kOk && !m.skip_unneeded && !m.grasp) unneeded_observers(m, d);
  return st;
}

// The environment does the work (fast::ToothContactProvider with the fast pipeline).
TickStatus collide(const PipelineModel& m, PipelineData& d) { return reference::collide(m, d); }

TickStatus assemble(const PipelineModel& m, PipelineData& d) {
  if (d.r.contacts.empty() && m.skip_unneeded) {
    d.contact = AffineWrench{};
  } else {
    d.contact = fast::contact_wrench_unchecked(d.r.contacts, d.proxy.pose, d.T, m.scheme);
    if (const AnchoredSpring* a = anchored_spring(d.env)) {  // the surface proxy (issue #32)
      fast::add_anchored_spring_unchecked(&d.contact, d.r.contacts, d.proxy.pose, d.T, m.scheme,
                                          *a, m.coupling.b_lin + m.proxy.damping_lin,
                                          m.coupling.b_ang + m.proxy.damping_ang);
    }
  }
  const TickStatus st = assemble_given_contact(m, d);
  if (st == TickStatus::kOk && !m.skip_unneeded && m.method != Method::kPmiPd) {
    unneeded_decomposition(m, d);
  }
  return st;
}

TickStatus solve(const PipelineModel& m, PipelineData& d) {
  if (m.skip_unneeded || m.friction.enabled || m.method == Method::kExplicitVc) {
    return reference::detail::solve_with(m, d, fast::pmi_try_solve,
                                         fast::solve_with_friction_unchecked, m.friction);
  }
  // Friction off, skips off: the friction solver at mu = 0 (its frictionless solution: the same
  // factor and solve as pmi_try_solve, so bitwise the skip's V_hat).
  static constexpr FrictionParams kNoFriction{true, 0.0};
  return reference::detail::solve_with(m, d, fast::pmi_try_solve,
                                       fast::solve_with_friction_unchecked, kNoFriction, true);
}

TickStatus command(const PipelineModel& m, PipelineData& d) { return reference::command(m, d); }

// Skipped (by the reference stage) unless the environment drills and the set is not empty; with
// skips off the environment is asked anyway (a provider that does not drill removes nothing).
TickStatus drill(const PipelineModel& m, PipelineData& d) {
  if (m.skip_unneeded) return reference::drill(m, d);
  d.r.removed_voxels = d.env->drill(d.r.contacts, d.T);
  if (d.env->drill_store_full()) return TickStatus::kDrillWorkTableFull;
  if (d.env->field_edit_shortfall()) return TickStatus::kFieldEditShortfall;
  return TickStatus::kOk;
}

TickStatus reset(const PipelineModel& m, PipelineData& d) {
  d.grip_gains = GripGainMemo{};  // the gains of another model's filter constants
  const TickStatus st = reference::reset(m, d);
  if (st != TickStatus::kOk || m.skip_unneeded || m.grasp) return st;
  // The observers the scene does not model start as the reference's would (skips off).
  const Vec6 beta = d.dev.CTqd - d.dev.g - d.dev.tau_f;
  const Vec6 Mqd = d.dev.M * d.qd;
  if (!m.observe) momentum_observer_reset<Vec6>(d.obs0, Mqd, beta);
  momentum_observer_reset<Vec6>(d.obs1, Mqd, beta);
  grip_filter_reset(m.grip, d.grip);
  return st;
}

const StageTable& fast_stage_table() {
  static const StageTable kTable = {
      "fast", {device_terms, observe, collide, assemble, solve, command, drill}, reset};
  return kTable;
}

}  // namespace dentsim::fast
