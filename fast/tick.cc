#include "fast/tick.h"

#include <limits>
#include <typeinfo>

#include "fast/contact.h"
#include "fast/decomposition.h"
#include "fast/dense6.h"
#include "fast/phantom/phantom_model.h"
#include "fast/pmi.h"
#include "reference/decomposition.h"
#include "reference/grip_detector.h"
#include "reference/observer.h"
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
// D_d are diagonal (PipelineModel::tool_diagonal, decided at setup); the reference's step otherwise.
bool pd_step(const PipelineModel& m, PipelineData& d) {
  if (!m.tool_diagonal) return reference::detail::pd_step(m, d);
  const TickResult& r = d.r;
  Mat6 M1;  // J1^T M J1 (2.2), M under the hypothesis in force (model_joint_inertia)
  if (m.grasp && d.grip.gripped) {
    inertia_at_tool(d.J1, reference::detail::model_joint_inertia(m, d, d.dev.M), &M1);
  } else {
    inertia_at_tool(d.J1, d.dev.M, &M1);
  }
  // A free tick with skips on: fast::assemble set d.contact to zero (no contact, no spring).
  // M1 from inertia_at_tool: exactly symmetric.
  const FeedforwardKnown known{m.skip_unneeded && r.contacts.empty(), true};
  return pd_feedforward_diagonal(M1, m.proxy, m.tool, r.device.R, d.proxy.pose.R, r.V1, r.F1_hat,
                                 d.contact, &d.pd_T1, &d.pd_T2, known);
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

}  // namespace

// The device model does the work (fast::PhantomModel with the fast pipeline); the stage around it
// (finite checks, V1, the hand's terms) is the reference's; J1 = J_t^-1 and the inertia's solve
// are fast/ kernels (above).
TickStatus device_terms(const PipelineModel& m, PipelineData& d) {
  return reference::detail::device_terms_with(m, d, invert_jacobian, solve_inertia);
}

// Two 6-vector observer updates: already allocation-free and O(36) flops; shared. Skipped (by the
// reference stage) without an observer gain; the grip detector only with a hand mass.
TickStatus observe(const PipelineModel& m, PipelineData& d) {
  const TickStatus st = reference::observe(m, d);
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
  const TickStatus st = reference::detail::assemble_given_contact_with(m, d, pd_step);
  if (st == TickStatus::kOk && !m.skip_unneeded && m.method != Method::kPmiPd) {
    unneeded_decomposition(m, d);
  }
  return st;
}

TickStatus solve(const PipelineModel& m, PipelineData& d) {
  if (m.skip_unneeded || m.friction.enabled || m.method == Method::kExplicitVc) {
    return reference::detail::solve_with(m, d, fast::pmi_try_solve, m.friction);
  }
  // Friction off, skips off: the friction solver at mu = 0 (its frictionless solution).
  static constexpr FrictionParams kNoFriction{true, 0.0};
  return reference::detail::solve_with(m, d, fast::pmi_try_solve, kNoFriction, true);
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
