// The shape control that stays passive under actuator saturation (reference/saturation_passive.h;
// issue #29 item 3; docs/derivations/quiet_stiffness.md section 6): its pieces against brute
// force, a press beyond the device's force on the simulated Phantom with it on and off (the proxy
// stays outside the tooth within the deliverable force over K_tooth, the hand port stays passive),
// unsaturated ticks bitwise unchanged, and the fast pipeline equal to the reference stage by stage
// on a saturated press.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "device/closed_loop.h"
#include "reference/saturation_passive.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "tests/support/crosscheck_rows.h"
#include "validation/crosscheck_fast.h"

namespace dentsim {
namespace {

bool within(const Vec6& tau, const Vec6& L, double headroom) {
  for (int i = 0; i < 6; ++i) {
    if (std::abs(tau(i)) > L(i) * (1.0 - headroom) * (1.0 + 1e-12)) return false;
  }
  return true;
}

TEST(SaturationPassive, DeliverableForceIsTheLargestWithinTheLimits) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Mat6 J;
    for (int i = 0; i < 36; ++i) J(i) = u(rng);
    Vec6 L, g;
    for (int i = 0; i < 6; ++i) {
      L(i) = 0.05 + 0.4 * std::abs(u(rng));
      g(i) = 0.3 * L(i) * u(rng);
    }
    const Vec3 dir = Vec3(u(rng), u(rng), u(rng)).normalized();
    const double F = deliverable_force(J, L, g, dir, kSaturationHeadroom);
    Vec6 w = Vec6::Zero();
    w.head<3>() = dir;
    const Vec6 per_n = J.transpose() * w;
    ASSERT_GT(F, 0.0);
    EXPECT_TRUE(within(F * per_n + g, L, kSaturationHeadroom)) << trial;
    EXPECT_FALSE(within(F * (1.0 + 1e-6) * per_n + g, L, kSaturationHeadroom)) << trial;
  }
  // Gravity alone beyond a limit: nothing deliverable.
  Vec6 L = Vec6::Constant(0.1), g = Vec6::Zero();
  g(2) = 0.2;
  EXPECT_EQ(deliverable_force(Mat6::Identity(), L, g, Vec3::UnitX(), 0.0), 0.0);
}

TEST(SaturationPassive, FeasibleScaleIsTheLargestWithinTheLimits) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int interior = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Vec6 a, b, L;
    for (int i = 0; i < 6; ++i) {
      L(i) = 0.1 + 0.3 * std::abs(u(rng));
      a(i) = 0.5 * L(i) * u(rng);
      b(i) = 1.5 * u(rng);
    }
    const double s = feasible_feedforward_scale(a, b, L, kSaturationHeadroom);
    ASSERT_GE(s, 0.0);
    ASSERT_LE(s, 1.0);
    EXPECT_TRUE(within(a + s * b, L, kSaturationHeadroom)) << trial;
    if (s < 1.0) {
      ++interior;
      EXPECT_FALSE(within(a + (s + 1e-6) * b, L, kSaturationHeadroom)) << trial;
    }
  }
  EXPECT_GT(interior, 100);
  // Already over a limit without the feed-forward, in its direction: 0.
  Vec6 a = Vec6::Zero(), b = Vec6::Zero(), L = Vec6::Constant(1.0);
  a(0) = 2.0;
  b(0) = 1.0;
  EXPECT_EQ(feasible_feedforward_scale(a, b, L, 0.0), 0.0);
}

TEST(SaturationPassive, TheCapLimitsTheSpringOnBothSidesAndOnlyAboveIt) {
  const double k = 1200.0;
  const Vec3 x1(0.0, 0.0, 0.0), x2(0.001, -0.002, 0.0005);  // |e| = 2.29 mm: 2.75 N
  AffineWrench p;
  p.f0.head<3>() = -k * (x2 - x1) + Vec3(0.1, 0.2, 0.3);  // plus a damper's part, kept
  Vec6 dev = Vec6::Zero();
  dev.head<3>() = k * (x2 - x1) + Vec3(-0.4, 0.0, 0.1);
  const AffineWrench p0 = p;
  const Vec6 dev0 = dev;
  EXPECT_FALSE(cap_coupling_spring(k, x1, x2, 3.0, &p, &dev));
  EXPECT_EQ(p.f0, p0.f0);
  EXPECT_EQ(dev, dev0);
  ASSERT_TRUE(cap_coupling_spring(k, x1, x2, 1.0, &p, &dev));
  const Vec3 e = (x2 - x1).normalized();
  EXPECT_NEAR((p.f0.head<3>() - Vec3(0.1, 0.2, 0.3) + 1.0 * e).norm(), 0.0, 1e-12);
  EXPECT_NEAR((dev.head<3>() - Vec3(-0.4, 0.0, 0.1) - 1.0 * e).norm(), 0.0, 1e-12);
  EXPECT_EQ(p.f0.tail<3>(), p0.f0.tail<3>());
}

// The static press of scripts/quiet_study.py (the built-in probe's method block, the explorer on
// the procedural molar, the hand's reference on the surface), shortened to a 1.5 s hold.
Scene press_scene(double press_n, double k_tooth, bool on) {
  char text[4096];
  std::snprintf(text, sizeof text, R"({
 "dentsim_scene": 1, "name": "saturated-press", "duration_s": 3.0, "tick_hz": 1000,
 "tooth": {"source": "procedural", "resolution": 128, "k_tooth_n_per_m": %g,
           "b_tooth_n_s_per_m": 5, "anchor_offset_mm": [0, 0, -6], "contact_model": "sdf"},
 "tool": {"preset": "explorer", "bur_radius_mm": 0.4, "bur_speed_rpm": 0},
 "device": {"type": "simulated-phantom", "jitter_us": 0, "quantize": true, "saturate": true},
 "method": {"name": "pmi-pd", "k_vc_n_per_m": 1200, "b_vc_n_s_per_m": 4,
            "k_vc_ang_n_m_per_rad": 0.3, "b_vc_ang_n_m_s_per_rad": 0.001,
            "observer_gain_per_s": 30, "friction_mu": 0, "grasp_mass_scale": 1.0,
            "grip_detector": true, "saturation_passive": %s},
 "proxy": {"mass_kg": 0.05, "inertia_kg_m2": 1e-5, "damping_n_s_per_m": 0,
           "damping_ang_n_m_s_per_rad": 0},
 "hand": {"script": [
  {"t_s": 0.0, "offset_mm": [0, 0, 6], "force_n": [0, 0, 0], "phase": "approach"},
  {"t_s": 1.0, "offset_mm": [0, 0, 1], "force_n": [0, 0, 0], "phase": "approach"},
  {"t_s": 1.5, "offset_mm": [0, 0, 0], "force_n": [0, 0, %g], "phase": "press"},
  {"t_s": 3.0, "offset_mm": [0, 0, 0], "force_n": [0, 0, %g], "phase": "press"}]}
})",
                k_tooth, on ? "true" : "false", -press_n, -press_n);
  return parse_scene(text, "saturation_passive_test");
}

struct PressRun {
  double max_proxy_depth_m = 0.0;   // over the run
  double max_device_depth_m = 0.0;  // over the run
  double max_cap_n = 0.0;           // the largest coupling force cap the pipeline used
  double min_sigma = 1.0;
  long engaged_ticks = 0;
  double hand_work_min_j = 0.0;
  double max_contact_force_n = 0.0;
  std::vector<std::string> faults;
  // The mechanism (section 6): when the command first saturated, and at the end of the hold the
  // command's demand per joint (|tau_i| unsaturated over L_i), the forces on the proxy and the
  // observer's estimate of the hand.
  double first_saturated_s = -1.0;
  long saturated_ticks = 0;
  Vec6 demand_first = Vec6::Zero(), demand_end = Vec6::Zero();
  double contact_end_n = 0.0, coupling_end_n = 0.0, hand_hat_end_n = 0.0, delivered_end_n = 0.0;
};

// |J_t^T T1 + g|_i / L_i: what the command asked of joint i before the uniform scaling.
Vec6 demand(const SceneRig& rig, const TickResult& t) {
  const auto& staged = dynamic_cast<const StagedPipeline&>(*rig.pipeline);
  const PipelineData& d = staged.data();
  const Vec6 tau = d.dev.J_t.transpose() * t.T1 + d.dev.g;
  return tau.cwiseAbs().cwiseQuotient(staged.model().torque_limit);
}

PressRun run_press(double press_n, double k_tooth, bool on) {
  const Scene scene = press_scene(press_n, k_tooth, on);
  RunOptions o;
  o.pipeline = "fast";
  const RunResult r = run_scene(scene, o);
  PressRun out;
  for (const RunSample& s : r.series) {
    out.max_proxy_depth_m = std::max(out.max_proxy_depth_m, s.penetration_m);
    out.max_device_depth_m = std::max(out.max_device_depth_m, s.device_penetration_m);
  }
  out.hand_work_min_j = r.hand_work_min_j;
  out.max_contact_force_n = r.max_contact_force_n;
  out.faults = r.faults;
  // The shape control's own signals, tick by tick on a rig of the same scene.
  SceneRigOptions ro;
  ro.pipeline = "fast";
  const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, ro);
  rig->loop->start();
  for (long k = 0; k < 3000 && !rig->loop->faulted(); ++k) {
    const TickResult& t = rig->loop->step();
    if (t.saturated) {
      if (out.first_saturated_s < 0.0) {
        out.first_saturated_s = 1e-3 * static_cast<double>(k);
        out.demand_first = demand(*rig, t);
      }
      ++out.saturated_ticks;
    }
    if (k == 2990) {
      out.demand_end = demand(*rig, t);
      out.contact_end_n = t.F_contact.head<3>().norm();
      out.coupling_end_n = t.F_coupling.head<3>().norm();
      out.hand_hat_end_n = t.F1_hat.head<3>().norm();
      // The force the device delivers: the scaled torque's wrench, J_t^-T (tau - g).
      const auto& staged = dynamic_cast<const StagedPipeline&>(*rig->pipeline);
      const PipelineData& d = staged.data();
      const Vec6 w = d.J1.transpose() * (Vec6(t.tau) - Vec6(t.tau_gravity));
      out.delivered_end_n = w.head<3>().norm();
    }
    out.max_cap_n = std::max(out.max_cap_n, t.coupling_force_cap);
    out.min_sigma = std::min(out.min_sigma, t.shape_sigma);
    if (t.shape_sigma < 1.0 || t.coupling_force_cap > 0.0) ++out.engaged_ticks;
  }
  return out;
}

// A 2 N press at K_tooth 3000 N/m asks more than the Phantom's continuous torques give at the
// tip (section 6). Off: the proxy ends ~4.5 mm in the tooth with ~13 N on it. On: the proxy's
// depth stays within the largest force the device could deliver along the coupling over K_tooth
// (+ 0.2 mm: the tooth's damping and the explorer tip's curvature at the contact), the hand port
// stays passive, and the contact force is bounded by that deliverable force (+ 20 %).
TEST(SaturationPassive, ASaturatedPressKeepsTheProxyOutsideAndTheHandPortPassive) {
  const double K = 3000.0;
  const PressRun off = run_press(2.0, K, false);
  const PressRun on = run_press(2.0, K, true);
  std::printf("off: proxy %.2f mm, device %.2f mm, contact max %.2f N, W_h min %.2e J, faults %zu\n",
              1e3 * off.max_proxy_depth_m, 1e3 * off.max_device_depth_m, off.max_contact_force_n,
              off.hand_work_min_j, off.faults.size());
  std::printf(
      "on:  proxy %.2f mm, device %.2f mm, contact max %.2f N, W_h min %.2e J, faults %zu, "
      "cap max %.2f N, sigma min %.3f, engaged %ld ticks\n",
      1e3 * on.max_proxy_depth_m, 1e3 * on.max_device_depth_m, on.max_contact_force_n,
      on.hand_work_min_j, on.faults.size(), on.max_cap_n, on.min_sigma, on.engaged_ticks);
  for (const PressRun* p : {&off, &on}) {
    std::printf(
        "  first saturated at %.3f s (demand/limit per joint %.2f %.2f %.2f %.2f %.2f %.2f), "
        "%ld saturated ticks; at 2.99 s: demand %.2f %.2f %.2f %.2f %.2f %.2f, contact %.2f N, "
        "coupling %.2f N, F1_hat %.2f N, delivered %.2f N\n",
        p->first_saturated_s, p->demand_first(0), p->demand_first(1), p->demand_first(2),
        p->demand_first(3), p->demand_first(4), p->demand_first(5), p->saturated_ticks,
        p->demand_end(0), p->demand_end(1), p->demand_end(2), p->demand_end(3), p->demand_end(4),
        p->demand_end(5), p->contact_end_n, p->coupling_end_n, p->hand_hat_end_n,
        p->delivered_end_n);
  }
  EXPECT_EQ(off.engaged_ticks, 0);
  ASSERT_GT(on.engaged_ticks, 100);
  EXPECT_LT(on.min_sigma, 0.5);
  const double bound = on.max_cap_n / K + 0.2e-3;
  EXPECT_GT(off.max_proxy_depth_m, 2.0 * bound);  // the failure it fixes
  EXPECT_LE(on.max_proxy_depth_m, bound);
  EXPECT_LE(on.max_contact_force_n, 1.2 * on.max_cap_n + 0.1);
  EXPECT_GE(on.hand_work_min_j, -1e-6);
}

// The built-in scenes at the stiffness they had before their quiet gains (K_tooth 12 000 N/m, the
// encoder Kalman filter off): their contact transients saturate the command. At the quiet gains
// (K_tooth 3000 N/m with the filter) none saturates, and on and off are the same run.
void stiff_as_before(Scene& s) {
  s.tooth.k_tooth = 12000.0;
  s.method.encoder_kalman = false;
}

// Across the central groove at 1 N (the probe-groove built-in, its hand's press patched), the
// saturated contact transients turn the hand port active without the shape control (energy flows
// into the hand: W_h min -2.3 mJ); with it the hand port stays passive (W_h >= -1 uJ) and the
// contact force's peak drops.
TEST(SaturationPassive, TheHandPortStaysPassiveAcrossTheGroove) {
  auto run = [](bool on) {
    Scene s = load_scene("probe-groove");
    stiff_as_before(s);
    s.method.saturation_passive = on;
    for (SceneHandKey& k : s.script) {
      if (k.phase == "probe") k.force = Vec3(0.0, 0.0, -1.0);
    }
    RunOptions o;
    o.pipeline = "fast";
    return run_scene(s, o);
  };
  const RunResult on = run(true), off = run(false);
  std::printf("groove 1 N: W_h min %.2e J (on) / %.2e J (off); contact max %.2f / %.2f N\n",
              on.hand_work_min_j, off.hand_work_min_j, on.max_contact_force_n,
              off.max_contact_force_n);
  EXPECT_LT(off.hand_work_min_j, -1e-4);  // the failure it fixes
  EXPECT_GE(on.hand_work_min_j, -1e-6);
  EXPECT_LT(on.max_contact_force_n, off.max_contact_force_n);
  EXPECT_TRUE(on.faults.empty());
}

// Until a command saturates, every tick is bitwise the same on and off: on the built-in probe
// (whose contact transients saturate a few ticks), every torque up to and including the first
// saturated tick's.
TEST(SaturationPassive, UnsaturatedTicksAreBitwiseUnchanged) {
  struct Run {
    std::vector<VecX> tau;
    long first_saturated = -1;
  };
  auto run = [](bool on) {
    Scene s = load_scene("probe");
    stiff_as_before(s);
    s.method.saturation_passive = on;
    SceneRigOptions ro;
    ro.pipeline = "fast";
    const std::unique_ptr<SceneRig> rig = build_scene_rig(s, ro);
    rig->loop->start();
    Run out;
    for (long k = 0; k < 2500; ++k) {
      const TickResult& r = rig->loop->step();
      out.tau.push_back(r.tau);
      if (r.saturated && out.first_saturated < 0) out.first_saturated = k;
    }
    return out;
  };
  const Run on = run(true), off = run(false);
  std::printf("probe: first saturated tick %ld (on) / %ld (off)\n", on.first_saturated,
              off.first_saturated);
  ASSERT_GT(off.first_saturated, 0);  // the check means something only if it saturates
  EXPECT_EQ(on.first_saturated, off.first_saturated);
  for (long k = 0; k <= off.first_saturated; ++k) {
    ASSERT_TRUE(on.tau[k] == off.tau[k]) << "tick " << k;
  }
}

// Stage by stage on a saturated press across the central groove (the probe-groove scene at 3 N):
// the fast pipeline equals the reference with the shape control on, within the crosscheck's bound.
TEST(SaturationPassive, FastPipelineEqualsTheReferenceOnASaturatedPress) {
  std::vector<StageConfig> configs;
  for (const char* cm : {"sdf", "faces"}) {
    StageConfig c;
    c.scene = "probe-groove";
    c.contact_model = cm;
    c.press_n = 3.0;
    c.saturation_passive = true;
    configs.push_back(c);
  }
  testing::expect_stage_configs_agree(configs, 2500);
  // The configuration does saturate, and the shape control engages in it.
  Scene scene = load_scene("probe-groove");
  scene.method.saturation_passive = true;
  for (SceneHandKey& k : scene.script) {
    if (k.force.norm() > 0.0) k.force = Vec3(0.0, 0.0, -3.0);
  }
  const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, SceneRigOptions{});
  rig->loop->start();
  long engaged = 0;
  for (long k = 0; k < 2500 && !rig->loop->faulted(); ++k) {
    if (rig->loop->step().shape_sigma < 1.0) ++engaged;
  }
  std::printf("probe-groove at 3 N: shape control engaged on %ld of 2500 ticks\n", engaged);
  EXPECT_GT(engaged, 10);
}

}  // namespace
}  // namespace dentsim
