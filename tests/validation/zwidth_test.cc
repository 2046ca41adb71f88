// Fast checks of the Z-width experiment (validation/zwidth.h) on the 1-DoF axis testbed
// (validation/zwidth_1dof.h): the same ClosedLoop, pipeline and voxel-slab contact as the
// simulated-Phantom sweep, one axis. The runs are deterministic (no jitter: seed 1 is printed
// for the record); every run holds >= 5 s of contact.
#include "validation/zwidth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

ZwidthScenario axis_scenario() {
  ZwidthScenario sc;
  sc.testbed = ZwidthTestbed::kAxis;
  std::printf("[zwidth] axis testbed: m_d %.3f kg, b_d %.4f N s/m, quantum %.3g m, seed %llu\n",
              sc.axis.mass, sc.axis.damping, sc.axis.quantum,
              static_cast<unsigned long long>(sc.seed));
  return sc;
}

TEST(ZwidthAxisDevice, FreeMassDampingAndQuantisation) {
  // Constant force u on the free device (no hand): v(t) = (u/b)(1 - exp(-b t/m)), exact
  // solution of m v' = u - b v. RK4 with 8 substeps per 1 ms tick matches it to 1e-9.
  AxisDeviceParams p;
  p.quantum = 1e-5;
  AxisDevice dev(p, Vec3(0, 0, 0.01));
  VecX tau = VecX::Zero(6);
  tau(2) = 0.5;
  tau(0) = 3.0;  // a constrained coordinate: ignored
  for (int k = 0; k < 200; ++k) {
    dev.write(tau);
    dev.advance();
  }
  const double t = dev.time();
  const double v = (0.5 / p.damping) * (1.0 - std::exp(-p.damping * t / p.mass));
  const double z = 0.01 + (0.5 / p.damping) * (t - (p.mass / p.damping) *
                                                       (1.0 - std::exp(-p.damping * t / p.mass)));
  EXPECT_NEAR(dev.true_vz(), v, 1e-9);
  EXPECT_NEAR(dev.true_z(), z, 1e-9);
  DeviceSample s = dev.make_sample();
  dev.read(s);
  EXPECT_DOUBLE_EQ(s.q(2), p.quantum * std::floor(dev.true_z() / p.quantum));
  EXPECT_EQ(s.q(0), 0.0);
  EXPECT_EQ(dev.applied_torque()(0), 0.0);
  // Saturation at the force limit.
  tau(2) = 20.0;
  dev.write(tau);
  EXPECT_DOUBLE_EQ(dev.applied_torque()(2), p.force_limit);
}

TEST(ZwidthAxisDevice, RejectsBadParameters) {
  AxisDeviceParams p;
  p.mass = -1.0;
  try {
    AxisDevice dev(p, Vec3::Zero());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("AxisDeviceParams.mass"), std::string::npos);
  }
  EXPECT_THROW(parse_operator("push"), InputError);
  EXPECT_THROW(parse_testbed("hapticmaster"), InputError);
}

TEST(ZwidthBounds, ClosedForms) {
  // Colgate-Schenkel K < 2 (b - B) / T; thesis §3.1 k_vc <= (b_d - b_vc (1 + T_k/T_k-1)) / T_k.
  EXPECT_DOUBLE_EQ(colgate_schenkel_max_stiffness(0.5, 0.1, 1e-3), 800.0);
  EXPECT_DOUBLE_EQ(colgate_schenkel_max_stiffness(0.1, 0.5, 1e-3), 0.0);
  EXPECT_DOUBLE_EQ(pmi_coupling_max_stiffness(0.5, 0.1, 1e-3, 1e-3), 300.0);
  EXPECT_DOUBLE_EQ(pmi_coupling_max_stiffness(0.5, 0.1, 1e-3, 0.5e-3), 200.0);
}

// Each method: a clearly stable, passive point (VC: the thesis's explicit gains with the coupling
// damping the explicit proxy needs; PD: K_tooth = 3000 N/m as in the thesis, with the stiff
// coupling that keeps the device on the proxy) and a clearly unstable one (stiff coupling and wall with almost no coupling
// damping).
TEST(ZwidthVerdicts, StableAndUnstablePointPerMethod) {
  const ZwidthScenario sc = axis_scenario();
  const ZwidthGains bad{3200.0, 0.1, 12000.0};
  for (Method m : {Method::kExplicitVc, Method::kPmiVc, Method::kPmiPd}) {
    const ZwidthGains good =
        m == Method::kPmiPd ? ZwidthGains{3200.0, 2.0, 3000.0} : ZwidthGains{400.0, 2.0, 1500.0};
    const ZwidthRun a = run_zwidth_once(m, ZwidthOperator::kForce, good, sc);
    const ZwidthRun b = run_zwidth_once(m, ZwidthOperator::kForce, bad, sc);
    std::printf(
        "[zwidth] %-8s good: stable %d passive %d lambda %.3f/s A %.3g m E_max %.3g J "
        "(tol %.3g) Z %.1f N/m | bad: stable %d passive %d lambda %.3f/s A %.3g m "
        "E_max %.3g J (tol %.3g) tunnelled %d\n",
        method_name(m), a.stable, a.passive, a.growth_rate_per_s, a.last_amplitude_m,
        a.energy_max_j, a.energy_tol_j, a.z_width_n_per_m, b.stable, b.passive, b.growth_rate_per_s,
        b.last_amplitude_m, b.energy_max_j, b.energy_tol_j, static_cast<int>(b.proxy_tunnelled));
    EXPECT_TRUE(a.stable) << method_name(m);
    EXPECT_TRUE(a.passive) << method_name(m);
    EXPECT_GE(a.contact_time_s, sc.hold_s - 2 * sc.tick);
    // At rest the force fed back balances the push: the static stiffness is the series
    // coupling-wall stiffness (PD: the wall's) within 10 %.
    const double series = good.k_vc * good.k_tooth / (good.k_vc + good.k_tooth);
    if (m != Method::kPmiPd) {
      EXPECT_NEAR(a.static_stiffness_n_per_m, series, 0.1 * series) << method_name(m);
    }
    EXPECT_FALSE(b.stable) << method_name(m);
  }
}

// The trend of the thesis (Fig. 4.11): the largest stable, passive Z-width under the force
// operator grows explicit < pmi < pmi-pd on a small grid.
TEST(ZwidthTrend, OrderingOnSmallGrid) {
  const ZwidthScenario sc = axis_scenario();
  ZwidthGrid g;
  g.k_vc = {400.0, 1600.0, 3200.0};
  g.b_vc = {2.0};
  g.k_tooth = {1500.0, 3000.0, 12000.0};
  const auto sw = run_zwidth_sweep({Method::kExplicitVc, Method::kPmiVc, Method::kPmiPd},
                                   {ZwidthOperator::kForce}, g, sc, 2);
  ASSERT_EQ(sw.size(), 3u);
  for (const ZwidthSweep& s : sw) {
    ASSERT_GE(s.best, 0) << method_name(s.method);
    const ZwidthGains& b = s.points[s.best].gains;
    std::printf("[zwidth] %-8s Z-width %.1f N/m at K_vc %.0f b_vc %.1f K_tooth %.0f\n",
                method_name(s.method), s.z_width_n_per_m(), b.k_vc, b.b_vc, b.k_tooth);
  }
  EXPECT_LT(sw[0].z_width_n_per_m(), sw[1].z_width_n_per_m());
  EXPECT_LT(sw[1].z_width_n_per_m(), sw[2].z_width_n_per_m());
  EXPECT_GE(sw[2].z_width_n_per_m(), 3000.0);
}

// Colgate-Schenkel on the explicit baseline where its assumptions hold: the proxy held by a very
// stiff, damped wall (K_tooth = 50000 N/m, B_tooth = 60 N s/m: the explicit proxy is stable since
// (K_vc + K_tooth) T < B_tooth + b_2 and B_tooth T / m_2 < 2), so the device sees a sampled spring
// K ~ K_vc to an almost fixed point; no coupling damping (B = 0); device damping b_d = 0.5 N s/m:
// passivity needs K < 2 b_d / T = 1000 N/m. Points at half and twice the bound fall on the
// predicted sides.
TEST(ZwidthColgateSchenkel, SeparatesExplicitPoints) {
  ZwidthScenario sc = axis_scenario();
  sc.axis.damping = 0.5;
  sc.b_tooth = 60.0;
  const double k_max = colgate_schenkel_max_stiffness(sc.axis.damping, 0.0, sc.tick);
  EXPECT_DOUBLE_EQ(k_max, 1000.0);
  for (double k_vc : {0.5 * k_max, 2.0 * k_max}) {
    const ZwidthRun r =
        run_zwidth_once(Method::kExplicitVc, ZwidthOperator::kForce, {k_vc, 0.0, 50000.0}, sc);
    std::printf(
        "[zwidth] CS: K_vc %.0f (bound %.0f): stable %d passive %d lambda %.3f/s A %.3g m "
        "E_max %.3g J\n",
        k_vc, k_max, r.stable, r.passive, r.growth_rate_per_s, r.last_amplitude_m, r.energy_max_j);
    const bool predicted = k_vc < k_max;
    EXPECT_EQ(r.stable && r.passive, predicted) << "K_vc " << k_vc;
  }
}

}  // namespace
}  // namespace dentsim

namespace dentsim {
namespace {

// PMI + PD with the literature hand gripping the tool (docs/derivations/decomposition_and_observer.md
// §8): without the hand's mass in the model the estimate carries -m_h a and the stiff wall
// (K_tooth = 12000 N/m) falls into a limit cycle; with the nominal mass in the model it holds.
TEST(ZwidthGraspMass, HandMassInTheModelStabilisesPmiPdUnderGrip) {
  ZwidthScenario sc;
  sc.testbed = ZwidthTestbed::kPhantom;
  sc.push_force_n = 1.0;
  const ZwidthGains g{3200.0, 2.0, 12000.0};
  const ZwidthRun without = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kGrip, g, sc);
  sc.grasp_mass_scale = 1.0;
  const ZwidthRun with = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kGrip, g, sc);
  std::printf("[zwidth] grip, pmi-pd (3200, 2, 12000): without grasp mass stable %d A %.3g m "
              "E_max %.3g J (tol %.3g) | with: stable %d passive %d A %.3g m Z %.0f N/m static "
              "%.0f N/m\n",
              without.stable, without.last_amplitude_m, without.energy_max_j, without.energy_tol_j,
              with.stable, with.passive, with.last_amplitude_m, with.z_width_n_per_m,
              with.static_stiffness_n_per_m);
  EXPECT_FALSE(without.stable);
  EXPECT_TRUE(with.stable);
  EXPECT_TRUE(with.passive);
  // Rendered at rest: the hand's spring shares the load, the wall stiffness dominates.
  EXPECT_GT(with.static_stiffness_n_per_m, 3000.0);
}

}  // namespace
}  // namespace dentsim

namespace dentsim {
namespace {

// The grip detector (reference/grip_detector.h, docs/derivations/decomposition_and_observer.md
// §9): with the hand's mass in the model, letting go leaves the model a mass that is not there
// and PMI + PD loses the wall; the detector drops the mass within tens of ms and keeps it while
// the hand grips; started "released" on a gripping hand, it finds the grip.
TEST(ZwidthGripDetector, DropsTheHandMassOnReleaseAndKeepsItUnderGrip) {
  ZwidthScenario sc;
  sc.testbed = ZwidthTestbed::kPhantom;
  sc.push_force_n = 1.0;
  sc.grasp_mass_scale = 1.0;
  const ZwidthGains g{3200.0, 2.0, 12000.0};
  const ZwidthRun fixed = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, g, sc);
  sc.grip_detector = true;
  const ZwidthRun release = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, g, sc);
  const ZwidthRun grip = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kGrip, g, sc);
  sc.grip_detector_params.start_gripped = false;
  const ZwidthRun found = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kGrip, g, sc);
  std::printf("[zwidth] pmi-pd (3200, 2, 12000), grasp mass 1: release without detector stable %d "
              "| with: stable %d passive %d detected after %.3f s, switches %d | grip: stable %d "
              "passive %d switches %d static %.0f N/m | grip from 'released': stable %d switches "
              "%d agreement %.3f\n",
              fixed.stable, release.stable, release.passive, release.release_detected_after_s,
              release.grip_switches, grip.stable, grip.passive, grip.grip_switches,
              grip.static_stiffness_n_per_m, found.stable, found.grip_switches,
              found.grip_agreement);
  EXPECT_FALSE(fixed.stable);
  EXPECT_EQ(fixed.grip_switches, 0);
  EXPECT_LT(fixed.release_detected_after_s, 0.0);  // no detector: never reported

  EXPECT_TRUE(release.stable);
  EXPECT_TRUE(release.passive);
  EXPECT_EQ(release.grip_switches, 1);
  EXPECT_GT(release.release_detected_after_s, 0.0);
  EXPECT_LT(release.release_detected_after_s, 0.05);  // measured 0.010 s

  EXPECT_TRUE(grip.stable);
  EXPECT_TRUE(grip.passive);
  EXPECT_EQ(grip.grip_switches, 0);
  EXPECT_DOUBLE_EQ(grip.grip_agreement, 1.0);
  EXPECT_GT(grip.static_stiffness_n_per_m, 3000.0);

  EXPECT_TRUE(found.stable);
  EXPECT_GE(found.grip_switches, 1);
  EXPECT_GT(found.grip_agreement, 0.5);
}

// `dentsim zwidth --device MODEL` (issue #29): the simulated device counts with the model file's
// encoder_counts_per_rev, and the tip quantum the verdicts use follows it. At the start pose
// q0 = 0 the tip moves along z by l1 per rad of q2 (the parallelogram keeps the forearm's angle),
// l_tip per rad of q3 and of the gimbal pitch (l_tip = 0.04 m, the tool offset), and not with q1,
// the yaw or the roll.
TEST(ZwidthPhantomDevice, TipQuantumFollowsTheModelFilesEncoders) {
  ZwidthScenario sc;
  sc.testbed = ZwidthTestbed::kPhantom;
  const PhantomParams base = default_phantom_params();
  const double l1 = base.l1_m, lt = -base.tip_offset_m.z();
  const auto quantum = [](const PhantomParams& p, int j) {
    return 2.0 * std::numbers::pi / p.encoder_counts_per_rev[j];
  };
  const double built_in = testbed_tip_quantum(sc);
  EXPECT_NEAR(built_in, l1 * quantum(base, 1) + lt * quantum(base, 2) + lt * quantum(base, 4),
              1e-12);
  PhantomParams fine = base;
  for (int j = 3; j < 6; ++j) fine.encoder_counts_per_rev[j] *= 4.0;  // gimbal 4 times finer
  sc.phantom_device_params = fine;
  const double finer = testbed_tip_quantum(sc);
  EXPECT_NEAR(built_in - finer, 0.75 * lt * quantum(base, 4), 1e-12);
  std::printf("[zwidth] tip quantum along z at q0: built-in %.4g m, gimbal x4 %.4g m\n", built_in,
              finer);
}

// A tap through the simulated Phantom (issue #29, the tap target): with the default clamp the
// force fed back along z at q0 is at most tau_max(q2) / l1 = 1.628 N; with the model file's
// thermal torque limit (peak 1.445 N m on q2) the same tap pushes past it, the motors stay far
// from their winding limit over a tap, and the device reports no fault.
TEST(ZwidthPhantomDevice, ThermalTorqueLimitLetsATapPastTheContinuousClamp) {
  ZwidthScenario sc;
  sc.testbed = ZwidthTestbed::kPhantom;
  sc.pipeline = "fast";
  sc.push_force_n = 1.0;
  sc.hold_s = 1.0;
  sc.observer_gain = 30.0;
  sc.grasp_mass_scale = 1.0;
  sc.grip_detector = true;
  const ZwidthGains gains{1600.0, 2.0, 3000.0};
  const PhantomParams base = default_phantom_params();
  const double f_clamp = base.torque_limit_n_m(1) / base.l1_m;
  const ZwidthRun clamp = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kTap, gains, sc, 0.3);
  PhantomParams thermal = base;
  thermal.torque_limit = phantom_thermal_torque_limit();
  sc.phantom_device_params = thermal;
  const ZwidthRun hot = run_zwidth_once(Method::kPmiPd, ZwidthOperator::kTap, gains, sc, 0.3);
  std::printf("[zwidth] tap 0.3 m/s at (1600, 2, 3000): clamp max force %.3f N (F_sat %.3f N, "
              "saturated %d), thermal max force %.3f N (saturated %d), Z-width %.0f / %.0f N/m\n",
              clamp.max_force_n, f_clamp, static_cast<int>(clamp.saturated), hot.max_force_n,
              static_cast<int>(hot.saturated), clamp.z_width_n_per_m, hot.z_width_n_per_m);
  EXPECT_TRUE(clamp.saturated);
  EXPECT_LE(clamp.max_force_n, f_clamp * (1.0 + 1e-3));  // the arm a little off q0 at impact
  EXPECT_GT(hot.max_force_n, 1.5 * f_clamp);
  EXPECT_EQ(hot.faults, 0u);
  EXPECT_GT(hot.z_width_n_per_m, 2.0 * clamp.z_width_n_per_m);
}

}  // namespace
}  // namespace dentsim
