#include "validation/crosscheck_fast.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <memory>
#include <numbers>

#include "sim/scene.h"
#include "sim/simulator.h"
#include "fast/registry.h"
#include "fast/tick.h"

namespace dentsim {
namespace {

// Largest |a - b|_inf / |a|_inf over the outputs added, where differences of at most 1e-15 (SI
// units) count as agreement: a near-zero output (C^T qd at qd ~ 1e-9 rad/s is ~1e-20 N m) differs
// by round-off that is large relative to itself and meaningless (docs/tolerance_policy.md 9).
constexpr double kAbsoluteFloor = 1e-15;

class Diff {
 public:
  template <class A, class B>
  void add(const A& a, const B& b) {
    const double scale = a.cwiseAbs().maxCoeff();
    const double d = (a - b).cwiseAbs().maxCoeff();
    add_scalar_pair(scale, d);
  }
  void scalar(double a, double b) { add_scalar_pair(std::abs(a), std::abs(a - b)); }
  void count(long a, long b) {
    if (a != b) ++mismatches;
  }
  double max_rel = 0.0;
  long mismatches = 0;

 private:
  void add_scalar_pair(double scale, double d) {
    if (!(d == d)) {  // NaN difference: a mismatch of the worst kind
      max_rel = INFINITY;
      return;
    }
    if (d <= kAbsoluteFloor) return;
    max_rel = std::max(max_rel, scale > 0.0 ? d / scale : INFINITY);
  }
};

void compare_stage(int stage, const PipelineData& a, const PipelineData& b, Diff* df) {
  switch (stage) {
    case kStageDeviceTerms:
      df->add(a.dev.M, b.dev.M);
      df->add(a.dev.CTqd, b.dev.CTqd);
      df->add(a.dev.g, b.dev.g);
      df->add(a.dev.tau_f, b.dev.tau_f);
      df->add(a.dev.J_t, b.dev.J_t);
      df->add(a.dev.J_t_dot, b.dev.J_t_dot);
      df->add(a.dev.pose.x, b.dev.pose.x);
      df->add(a.dev.pose.R, b.dev.pose.R);
      df->add(a.J1, b.J1);
      df->add(a.r.V1, b.r.V1);
      df->add(a.M_hand, b.M_hand);
      df->add(a.CTqd_hand, b.CTqd_hand);
      break;
    case kStageObserve:
      df->add(a.r.F1_hat, b.r.F1_hat);
      df->add(a.obs0.p_hat, b.obs0.p_hat);
      df->add(a.obs0.f_hat, b.obs0.f_hat);
      df->add(a.obs1.f_hat, b.obs1.f_hat);
      df->scalar(a.grip.p0, b.grip.p0);
      df->scalar(a.grip.p1, b.grip.p1);
      df->count(a.r.grip_state, b.r.grip_state);
      break;
    case kStageCollide:
      df->count(static_cast<long>(a.r.contacts.size()), static_cast<long>(b.r.contacts.size()));
      if (a.r.contacts.size() == b.r.contacts.size()) {
        for (std::size_t i = 0; i < a.r.contacts.size(); ++i) {
          const Contact& p = a.r.contacts[i];
          const Contact& q = b.r.contacts[i];
          df->add(p.x_o, q.x_o);
          df->add(p.n, q.n);
          df->add(p.r, q.r);
          df->scalar(p.depth, q.depth);
          df->scalar(p.stiffness, q.stiffness);
          df->scalar(p.damping, q.damping);
          df->scalar(p.weight, q.weight);
          df->count(p.material, q.material);
        }
      }
      df->scalar(a.r.max_depth, b.r.max_depth);
      break;
    case kStageAssemble:
      df->add(a.coupling.f0, b.coupling.f0);
      df->add(a.coupling.G, b.coupling.G);
      df->add(a.contact.f0, b.contact.f0);
      df->add(a.contact.G, b.contact.G);
      // The fast twin keeps T1 factored (PipelineData::pd_T1_factored): compared formed.
      df->add(pd_T1_formed(a).f0, pd_T1_formed(b).f0);
      df->add(pd_T1_formed(a).G, pd_T1_formed(b).G);
      df->add(a.pd_T2.f0, b.pd_T2.f0);
      df->add(a.pd_T2.G, b.pd_T2.G);
      df->add(a.sys.A, b.sys.A);
      df->add(a.sys.b, b.sys.b);
      df->add(a.r.T1_vc, b.r.T1_vc);
      break;
    case kStageSolve:
      df->add(a.r.V_hat, b.r.V_hat);
      df->add(a.proxy.pose.x, b.proxy.pose.x);
      df->add(a.proxy.pose.R, b.proxy.pose.R);
      df->add(a.proxy.V, b.proxy.V);
      df->add(a.r.F_contact, b.r.F_contact);
      df->add(a.r.F_coupling, b.r.F_coupling);
      df->add(a.r.T1_pd, b.r.T1_pd);
      break;
    case kStageCommand:
      df->add(a.r.tau, b.r.tau);
      df->add(a.r.T1, b.r.T1);
      df->add(a.r.tau_gravity, b.r.tau_gravity);
      break;
    case kStageDrill:
      df->count(a.r.removed_voxels, b.r.removed_voxels);
      break;
    default:
      break;
  }
}

// The adversarial perturbations (crosscheck_fast.h), applied to a copy of a tick's starting state.
struct Perturbation {
  const char* name;
  double T;              // > 0: the tick length
  double angle;          // >= 0: the proxy's rotation off the device's orientation [rad]
  bool saturate;         // the model with torque limits at 1 %
  double proxy_depth_m;  // > 0: the proxy moved this far down (-z)
  bool frictionless;     // the model without friction (the PMI solve of the contact system)
};
constexpr Perturbation kPerturbations[] = {
    {"tick_1e-5", 1e-5, -1.0, false, 0.0, false},
    {"tick_1e-4", 1e-4, -1.0, false, 0.0, false},
    {"tick_1e-2", 1e-2, -1.0, false, 0.0, false},
    {"rotation_near_0", 0.0, 1e-9, false, 0.0, false},
    {"rotation_near_pi", 0.0, std::numbers::pi - 1e-9, false, 0.0, false},
    {"saturation", 0.0, -1.0, true, 0.0, false},
    {"proxy_offset", 0.0, -1.0, false, 3e-4, false},
    {"frictionless", 0.0, -1.0, false, 0.0, true},
};
constexpr int kPerturbationCount = static_cast<int>(std::size(kPerturbations));

void perturb(const Perturbation& p, long k, PipelineData* d) {
  if (p.T > 0.0) d->T = p.T;
  if (p.angle >= 0.0) {
    // A different axis each time (a fixed sequence: reproducible).
    const double a = 0.7 * static_cast<double>(k);
    const Vec3 axis = Vec3(std::cos(a), std::sin(a), 0.5 * std::cos(1.3 * a)).normalized();
    d->proxy.pose.R = d->r.device.R * Eigen::AngleAxisd(p.angle, axis).toRotationMatrix();
  }
  if (p.proxy_depth_m > 0.0) d->proxy.pose.x.z() -= p.proxy_depth_m;
}

const StagedPipeline& staged(const SceneRig& rig) {
  return dynamic_cast<const StagedPipeline&>(*rig.pipeline);
}

// A built-in scene as a configuration asks for it.
Scene config_scene(const StageConfig& c) {
  Scene scene = load_scene(c.scene);
  scene.method.method = c.method;
  scene.method.grasp_mass_scale = 1.0;  // the hand's terms in every configuration
  scene.method.grip_detector = c.grip_detector;
  scene.tooth.contact_model = c.contact_model;
  scene.method.lag_compensation = c.lag_compensation;
  scene.method.saturation_passive = c.saturation_passive;
  if (c.press_n > 0.0) {
    for (SceneHandKey& k : scene.script) {
      if (k.force.norm() > 0.0) k.force = Vec3(0.0, 0.0, -c.press_n);
    }
  }
  return scene;
}

std::unique_ptr<SceneRig> rig_of(const Scene& scene, const std::string& pipeline) {
  SceneRigOptions ro;
  ro.pipeline = pipeline;
  return build_scene_rig(scene, ro);
}

std::string sci(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3e", x);
  return b;
}

void add_row(const FastCrosscheckOptions& o, StageCrosscheck c, FastCrosscheckResult* out) {
  if (!(c.max_rel <= o.max_rel_bound) || c.count_mismatches != 0) {
    out->ok = false;
    out->failures.push_back(c.implementation + " " + c.config + " " + c.stage + ": max_rel " +
                            sci(c.max_rel) + ", count mismatches " +
                            std::to_string(c.count_mismatches));
  }
  out->stages.push_back(std::move(c));
}

// Stage by stage on one configuration: `ref` runs in closed loop, the other implementation's
// stages run on copies of its data (its own environment `other`), and its stages from observe on
// run chained on a copy of the reference's device terms, on a third environment (`chain`) that
// sees the same queries.
void check_config(const StageConfig& cfg, const CheckedImplementation& impl,
                  const FastCrosscheckOptions& o, FastCrosscheckResult* out) {
  const Scene scene = config_scene(cfg);
  const std::string config = cfg.name();
  const std::unique_ptr<SceneRig> ref = rig_of(scene, "reference");
  const std::unique_ptr<SceneRig> other = rig_of(scene, impl.environment);
  const std::unique_ptr<SceneRig> chain = rig_of(scene, impl.environment);
  // The adversarial states query their own pair of environments (header).
  std::unique_ptr<SceneRig> ref_adv, other_adv;
  if (o.adversarial) {
    ref_adv = rig_of(scene, "reference");
    other_adv = rig_of(scene, impl.environment);
  }
  const StageTable& ref_table = reference_stage_table();
  const StageTable& table = *impl.table;
  bool shared[kStageCount] = {};
  for (int i : impl.shared_stages) {
    if (i >= 0 && i < kStageCount) shared[i] = true;
  }
  const PipelineModel& m_ref = staged(*ref).model();
  const PipelineModel& m_other = staged(*other).model();
  const PipelineModel& m_chain = staged(*chain).model();
  Diff diffs[kStageCount];
  Diff chain_diff;  // the implementation's chained stages against the reference's
  long samples = 0, contact_samples = 0;
  // Adversarial: the models with torque limits at 1 %, the diffs per perturbation and stage.
  PipelineModel m_ref_sat = m_ref, m_other_sat = m_other;
  m_ref_sat.torque_limit *= 0.01;
  m_other_sat.torque_limit *= 0.01;
  PipelineModel m_ref_nof = m_ref, m_other_nof = m_other;
  m_ref_nof.friction.enabled = false;
  m_other_nof.friction.enabled = false;
  Diff adv[kPerturbationCount][kStageCount - 1];
  long adv_samples[kPerturbationCount] = {}, adv_contact[kPerturbationCount] = {};
  long adv_saturated[kPerturbationCount] = {};
  auto P = std::make_unique<PipelineData>();
  Device& dev = *ref->device;
  DeviceSample s = dev.make_sample();
  dev.read(s);
  auto D = std::make_unique<PipelineData>();
  auto C = std::make_unique<PipelineData>();
  auto E = std::make_unique<PipelineData>();
  if (pipeline_reset(ref_table, m_ref, *D, s) != TickStatus::kOk) {
    out->failures.push_back(config + ": the reference could not start");
    out->ok = false;
    return;
  }
  double T = dev.capabilities().nominal_period;
  for (long k = 0; k < o.stage_ticks; ++k) {
    D->q = s.q;
    D->qd = s.qd;
    D->t = s.t;
    D->T = T;
    D->env = ref->contacts;
    if (o.adversarial && k > 0) {
      // One perturbation per tick, in turn, on a copy of the tick's starting state; every stage
      // but drill (it would cut the teeth).
      const int pi = static_cast<int>(k % kPerturbationCount);
      const Perturbation& pt = kPerturbations[pi];
      *P = *D;
      P->env = ref_adv->contacts;
      perturb(pt, k, P.get());
      const PipelineModel& mr = pt.saturate ? m_ref_sat : pt.frictionless ? m_ref_nof : m_ref;
      const PipelineModel& mo = pt.saturate ? m_other_sat : pt.frictionless ? m_other_nof : m_other;
      bool ok_adv = true;
      for (int i = 0; i < kStageCount - 1 && ok_adv; ++i) {
        *C = *P;
        C->env = other_adv->contacts;
        const TickStatus so = table.stage[i](mo, *C);
        const TickStatus sr = ref_table.stage[i](mr, *P);
        if (so != sr) adv[pi][i].mismatches++;
        ok_adv = sr == TickStatus::kOk && so == TickStatus::kOk;
        if (!shared[i]) compare_stage(i, *P, *C, &adv[pi][i]);
      }
      ++adv_samples[pi];
      if (!P->r.contacts.empty()) ++adv_contact[pi];
      if (ok_adv && P->r.saturated) ++adv_saturated[pi];
    }
    bool ok = true;
    for (int i = 0; i < kStageCount && ok; ++i) {
      *C = *D;
      C->env = other->contacts;
      const TickStatus so = table.stage[i](m_other, *C);
      const TickStatus sr = ref_table.stage[i](m_ref, *D);
      if (so != sr) diffs[i].mismatches++;
      ok = sr == TickStatus::kOk;
      if (!shared[i]) compare_stage(i, *D, *C, &diffs[i]);
      if (i == kStageDeviceTerms) {
        *E = *D;  // the chain starts on the reference's device terms (header)
        E->env = chain->contacts;
      }
    }
    // The implementation's stages from observe on, chained (the reference's ran to its end when
    // ok).
    if (ok) {
      for (int i = kStageDeviceTerms + 1; i < kStageCount; ++i) {
        if (table.stage[i](m_chain, *E) != TickStatus::kOk) {
          ++chain_diff.mismatches;
          break;
        }
      }
      for (int i = kStageDeviceTerms + 1; i < kStageCount; ++i) {
        compare_stage(i, *D, *E, &chain_diff);
      }
    }
    ++samples;
    if (!D->r.contacts.empty()) ++contact_samples;
    for (const Contact& c : D->r.contacts) {
      const auto m = static_cast<std::size_t>(c.material);
      if (c.material >= 0 && m < out->contact_members_per_material.size()) {
        ++out->contact_members_per_material[m];
      }
    }
    if (!ok) break;
    dev.write(D->r.tau);
    dev.advance();
    const double t_prev = s.t;
    dev.read(s);
    if (s.t > t_prev) T = s.t - t_prev;
  }
  StageCrosscheck row;
  row.implementation = table.implementation;
  row.config = config;
  row.samples = samples;
  row.contact_samples = contact_samples;
  for (int i = 0; i < kStageCount; ++i) {
    if (shared[i]) continue;
    row.stage = tick_stage_name(i);
    row.max_rel = diffs[i].max_rel;
    row.count_mismatches = diffs[i].mismatches;
    add_row(o, row, out);
  }
  row.stage = "chain";
  row.max_rel = chain_diff.max_rel;
  row.count_mismatches = chain_diff.mismatches;
  add_row(o, row, out);
  for (int pi = 0; pi < kPerturbationCount && o.adversarial; ++pi) {
    for (int i = 0; i < kStageCount - 1; ++i) {
      if (shared[i]) continue;
      AdversarialCrosscheck c;
      c.implementation = table.implementation;
      c.config = config;
      c.perturbation = kPerturbations[pi].name;
      c.stage = tick_stage_name(i);
      c.max_rel = adv[pi][i].max_rel;
      c.samples = adv_samples[pi];
      c.contact_samples = adv_contact[pi];
      c.count_mismatches = adv[pi][i].mismatches;
      c.saturated_samples = adv_saturated[pi];
      if (!(c.max_rel <= o.max_rel_bound) || c.count_mismatches != 0) {
        out->ok = false;
        out->failures.push_back(c.implementation + " " + config + " " + c.perturbation + " stage " +
                                c.stage + ": max_rel " + sci(c.max_rel) + ", count mismatches " +
                                std::to_string(c.count_mismatches));
      }
      out->adversarial.push_back(c);
    }
  }
}

void check_scene(const std::string& name, const CheckedImplementation& impl,
                 const FastCrosscheckOptions& o, FastCrosscheckResult* out) {
  const StageTable& table = *impl.table;
  if (find_stage_table(impl.environment) != &table) {
    // The closed loop runs a registered pipeline (build_scene_rig): a test's wrapper table has
    // none.
    out->ok = false;
    out->failures.push_back(name + ": the closed loop runs registered implementations only (" +
                            table.implementation + ")");
    return;
  }
  // "NAME:faces": the built-in scene with the face contact model (the one with a fast twin).
  const std::size_t colon = name.find(':');
  Scene scene = load_scene(name.substr(0, colon));
  if (colon != std::string::npos) scene.tooth.contact_model = name.substr(colon + 1);
  SceneRigOptions ro;
  ro.pipeline = "reference";
  const std::unique_ptr<SceneRig> a = build_scene_rig(scene, ro);
  ro.pipeline = table.implementation;
  const std::unique_ptr<SceneRig> b = build_scene_rig(scene, ro);
  SceneCrosscheck c;
  c.scene = name;
  c.implementation = table.implementation;
  a->loop->start();
  b->loop->start();
  const long n = static_cast<long>(std::ceil(o.scene_duration_s * scene.tick_hz));
  c.t.reserve(n);
  c.force_diff_n.reserve(n);
  for (long k = 0; k < n; ++k) {
    const double t = a->loop->sample().t;
    const TickResult& ra = a->loop->step();
    const TickResult& rb = b->loop->step();
    if (a->loop->faulted() || b->loop->faulted()) {
      out->ok = false;
      out->failures.push_back(name + ": a loop faulted (" + a->loop->fault_name() + ", " +
                              b->loop->fault_name() + ")");
      break;
    }
    const double fa = ra.T1.head<3>().norm();
    const double diff = (ra.T1.head<3>() - rb.T1.head<3>()).norm();
    ++c.ticks;
    if (!ra.contacts.empty()) {
      ++c.contact_ticks;
      if (c.first_contact_s < 0.0) c.first_contact_s = t;
    }
    if (c.first_contact_s < 0.0) {
      c.max_force_diff_before_contact_n = std::max(c.max_force_diff_before_contact_n, diff);
    }
    c.max_force_diff_n = std::max(c.max_force_diff_n, diff);
    c.max_force_n = std::max(c.max_force_n, fa);
    if (diff > 1e-9 && c.diverged_1e9_s < 0.0) c.diverged_1e9_s = t;
    if (diff > 1e-6 && c.diverged_1e6_s < 0.0) c.diverged_1e6_s = t;
    if (diff > 1e-3 && c.diverged_1e3_s < 0.0) c.diverged_1e3_s = t;
    c.t.push_back(t);
    c.force_diff_n.push_back(diff);
  }
  // Bounds: round-off before the first contact; never more than the force being rendered.
  if (!(c.max_force_diff_before_contact_n <= 1e-9)) {
    out->ok = false;
    out->failures.push_back(name + ": force differs by " +
                            std::to_string(c.max_force_diff_before_contact_n) +
                            " N before the first contact (bound 1e-9 N)");
  }
  if (!(c.max_force_diff_n <= c.max_force_n)) {
    out->ok = false;
    out->failures.push_back(name + ": force difference " + std::to_string(c.max_force_diff_n) +
                            " N exceeds the largest force rendered");
  }
  out->scenes.push_back(std::move(c));
}

}  // namespace

std::string StageConfig::name() const {
  return scene + "/" + contact_model + "/" + method_name(method) + (grip_detector ? "+grip" : "") +
         (lag_compensation ? "+lag" : "") + (saturation_passive ? "+satpass" : "") +
         (press_n > 0.0 ? "+press" + std::to_string(press_n).substr(0, 4) + "N" : "");
}

namespace {
// The (method, grip detector, contact model) combinations, in a fixed order.
std::vector<StageConfig> combinations() {
  std::vector<StageConfig> v;
  for (Method m : {Method::kExplicitVc, Method::kPmiVc, Method::kPmiPd}) {
    for (bool grip : {false, true}) {
      for (const char* model : {"sdf", "faces"}) {
        StageConfig c;
        c.method = m;
        c.grip_detector = grip;
        c.contact_model = model;
        v.push_back(c);
      }
    }
  }
  return v;
}
}  // namespace

std::vector<StageConfig> stage_config_matrix(const std::vector<std::string>& scenes) {
  std::vector<StageConfig> v;
  for (const std::string& s : scenes) {
    for (StageConfig c : combinations()) {
      c.scene = s;
      v.push_back(c);
    }
  }
  return v;
}

std::vector<StageConfig> stage_config_cover(const std::vector<std::string>& scenes) {
  std::vector<StageConfig> v = combinations();
  if (scenes.empty()) return {};
  for (std::size_t i = 0; i < v.size(); ++i) v[i].scene = scenes[i % scenes.size()];
  return v;
}

std::vector<CheckedImplementation> registered_implementations() {
  std::vector<CheckedImplementation> v;
  for (const StageTable* t : stage_tables()) {
    if (t == &reference_stage_table()) continue;
    CheckedImplementation c;
    c.table = t;
    c.environment = t->implementation;
    // fast/tick.cc: observe and command are the reference's stages (the skips' extra work is
    // discarded, and the crosscheck runs with skips on).
    if (t == &fast::fast_stage_table()) c.shared_stages = {kStageObserve, kStageCommand};
    v.push_back(std::move(c));
  }
  return v;
}

FastCrosscheckResult crosscheck_fast(const FastCrosscheckOptions& options) {
  FastCrosscheckResult res;
  const std::vector<CheckedImplementation> impls =
      options.implementations.empty() ? registered_implementations() : options.implementations;
  for (const CheckedImplementation& impl : impls) {
    for (int i : impl.shared_stages) {
      res.shared.push_back({impl.table->implementation, tick_stage_name(i),
                            "runs the reference's own code: on the same input a row would compare "
                            "a function with itself; its outputs are compared in the chain row"});
    }
    const auto stop = [&](const std::string& next) {
      if (options.stop_request == nullptr || !options.stop_request->load()) return false;
      res.stopped = true;
      res.stopped_at = std::string(impl.table->implementation) + " " + next;
      return true;
    };
    for (const StageConfig& c : options.stage_configs) {
      if (stop("configuration " + c.name())) return res;
      check_config(c, impl, options, &res);
    }
    for (const std::string& name : options.scenes) {
      if (stop("scene " + name)) return res;
      check_scene(name, impl, options, &res);
    }
  }
  return res;
}

}  // namespace dentsim
