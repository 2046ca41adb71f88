#include "validation/crosscheck_fast.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <memory>
#include <numbers>

#include "sim/scene.h"
#include "sim/simulator.h"
#include "fast/registry.h"

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
      df->add(a.pd_T1.f0, b.pd_T1.f0);
      df->add(a.pd_T1.G, b.pd_T1.G);
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
};
constexpr Perturbation kPerturbations[] = {
    {"tick_1e-5", 1e-5, -1.0, false, 0.0},
    {"tick_1e-4", 1e-4, -1.0, false, 0.0},
    {"tick_1e-2", 1e-2, -1.0, false, 0.0},
    {"rotation_near_0", 0.0, 1e-9, false, 0.0},
    {"rotation_near_pi", 0.0, std::numbers::pi - 1e-9, false, 0.0},
    {"saturation", 0.0, -1.0, true, 0.0},
    {"proxy_offset", 0.0, -1.0, false, 3e-4},
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

// Stage by stage on the drill scene: `ref` runs in closed loop, the other implementation's stages
// run on copies of its data.
void check_stages(const FastCrosscheckOptions& o, FastCrosscheckResult* out) {
  Scene scene = load_scene("drill");
  scene.method.grasp_mass_scale = 1.0;  // exercise the hand's terms and the grip detector too
  scene.method.grip_detector = true;
  // The face contact model: the one with a fast twin (fast/tooth/), so `collide` and `drill`
  // compare the brick tooth with the reference octree.
  scene.tooth.contact_model = "faces";
  SceneRigOptions ro;
  ro.pipeline = "reference";
  const std::unique_ptr<SceneRig> ref = build_scene_rig(scene, ro);
  const StageTable& ref_table = reference_stage_table();
  for (const StageTable* table : stage_tables()) {
    if (table == &ref_table) continue;
    ro.pipeline = table->implementation;
    const std::unique_ptr<SceneRig> other = build_scene_rig(scene, ro);
    const PipelineModel& m_ref = staged(*ref).model();
    const PipelineModel& m_other = staged(*other).model();
    Diff diffs[kStageCount];
    long samples = 0, contact_samples = 0;
    // Adversarial: the models with torque limits at 1 %, the diffs per perturbation and stage.
    PipelineModel m_ref_sat = m_ref, m_other_sat = m_other;
    m_ref_sat.torque_limit *= 0.01;
    m_other_sat.torque_limit *= 0.01;
    Diff adv[kPerturbationCount][kStageCount - 1];
    long adv_samples[kPerturbationCount] = {}, adv_contact[kPerturbationCount] = {};
    long adv_saturated[kPerturbationCount] = {};
    auto P = std::make_unique<PipelineData>();
    Device& dev = *ref->device;
    DeviceSample s = dev.make_sample();
    dev.read(s);
    auto D = std::make_unique<PipelineData>();
    auto C = std::make_unique<PipelineData>();
    if (pipeline_reset(ref_table, m_ref, *D, s) != TickStatus::kOk) {
      out->failures.push_back("stage crosscheck: the reference could not start");
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
        // but drill (it would cut the teeth the main comparison drills).
        const int pi = static_cast<int>(k % kPerturbationCount);
        const Perturbation& pt = kPerturbations[pi];
        *P = *D;
        perturb(pt, k, P.get());
        const PipelineModel& mr = pt.saturate ? m_ref_sat : m_ref;
        const PipelineModel& mo = pt.saturate ? m_other_sat : m_other;
        bool ok_adv = true;
        for (int i = 0; i < kStageCount - 1 && ok_adv; ++i) {
          *C = *P;
          C->env = other->contacts;
          const TickStatus so = table->stage[i](mo, *C);
          const TickStatus sr = ref_table.stage[i](mr, *P);
          if (so != sr) adv[pi][i].mismatches++;
          ok_adv = sr == TickStatus::kOk && so == TickStatus::kOk;
          compare_stage(i, *P, *C, &adv[pi][i]);
        }
        ++adv_samples[pi];
        if (!P->r.contacts.empty()) ++adv_contact[pi];
        if (ok_adv && P->r.saturated) ++adv_saturated[pi];
      }
      bool ok = true;
      for (int i = 0; i < kStageCount && ok; ++i) {
        *C = *D;
        C->env = other->contacts;
        const TickStatus so = table->stage[i](m_other, *C);
        const TickStatus sr = ref_table.stage[i](m_ref, *D);
        if (so != sr) diffs[i].mismatches++;
        ok = sr == TickStatus::kOk;
        compare_stage(i, *D, *C, &diffs[i]);
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
    for (int i = 0; i < kStageCount; ++i) {
      StageCrosscheck c;
      c.implementation = table->implementation;
      c.stage = tick_stage_name(i);
      c.max_rel = diffs[i].max_rel;
      c.samples = samples;
      c.contact_samples = contact_samples;
      c.count_mismatches = diffs[i].mismatches;
      if (!(c.max_rel <= o.max_rel_bound) || c.count_mismatches != 0) {
        out->ok = false;
        out->failures.push_back(c.implementation + " stage " + c.stage + ": max_rel " +
                                std::to_string(c.max_rel) + ", count mismatches " +
                                std::to_string(c.count_mismatches));
      }
      out->stages.push_back(c);
    }
    for (int pi = 0; pi < kPerturbationCount && o.adversarial; ++pi) {
      for (int i = 0; i < kStageCount - 1; ++i) {
        AdversarialCrosscheck c;
        c.implementation = table->implementation;
        c.perturbation = kPerturbations[pi].name;
        c.stage = tick_stage_name(i);
        c.max_rel = adv[pi][i].max_rel;
        c.samples = adv_samples[pi];
        c.contact_samples = adv_contact[pi];
        c.count_mismatches = adv[pi][i].mismatches;
        c.saturated_samples = adv_saturated[pi];
        if (!(c.max_rel <= o.max_rel_bound) || c.count_mismatches != 0) {
          out->ok = false;
          out->failures.push_back(c.implementation + " " + c.perturbation + " stage " + c.stage +
                                  ": max_rel " + std::to_string(c.max_rel) + ", count mismatches " +
                                  std::to_string(c.count_mismatches));
        }
        out->adversarial.push_back(c);
      }
    }
  }
}

void check_scene(const std::string& name, const StageTable& table, const FastCrosscheckOptions& o,
                 FastCrosscheckResult* out) {
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

FastCrosscheckResult crosscheck_fast(const FastCrosscheckOptions& options) {
  FastCrosscheckResult res;
  check_stages(options, &res);
  for (const StageTable* table : stage_tables()) {
    if (table == &reference_stage_table()) continue;
    for (const std::string& name : options.scenes) check_scene(name, *table, options, &res);
  }
  return res;
}

}  // namespace dentsim
