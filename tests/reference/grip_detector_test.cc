// Tests for reference/grip_detector.h on the analytic Phantom model driven through its own
// dynamics: a plant that carries the hand's mass is judged gripped, one without it released, the
// right hypothesis explains the motion with (nearly) no human force, and nothing switches at rest.
#include "reference/grip_detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "reference/phantom/phantom_model.h"
#include "reference/two_link_model.h"

namespace dentsim {
namespace {

constexpr double kMass = 0.554;    // the literature hand (device/scripted_hand.h)
constexpr double kInertia = 2e-4;  // [kg m^2]
constexpr double kT = 1e-3;
constexpr int kSubsteps = 10;

struct Outcome {
  bool gripped = false;
  int switches = 0;
  double statistic = 0.0;
  double rms_h0 = 0.0, rms_h1 = 0.0;  // linear force of each hypothesis's estimate [N], last half
  double tip_travel = 0.0;            // max |x - x0| [m]
};

// Drives `plant` (gravity compensated) with a joint torque of `amp` N m at `hz` on the first three
// joints for `seconds`, with no human force, and runs the detector on it.
Outcome drive(const SixDofDeviceModel& plant, GripDetector& det, double amp, double hz,
              double seconds) {
  const PhantomParams p = default_phantom_params();
  VecX q(6);
  for (int j = 0; j < 6; ++j) q(j) = 0.5 * (p.q_min_rad(j) + p.q_max_rad(j));
  VecX qd = VecX::Zero(6);
  det.reset(q, qd);
  const Vec3 x0 = plant.forward_kinematics(q).x;
  Outcome out;
  bool last = det.gripped();
  const int n = static_cast<int>(seconds / kT);
  double s0 = 0.0, s1 = 0.0;
  int m = 0;
  for (int k = 0; k < n; ++k) {
    VecX tau = plant.gravity(q);
    const double w = 2.0 * std::numbers::pi * hz * k * kT;
    tau(0) += amp * std::sin(w);
    tau(1) += amp * std::sin(w + 1.0);
    tau(2) += amp * std::sin(w + 2.0);
    for (int i = 0; i < kSubsteps; ++i) rk4_step(plant, tau, kT / kSubsteps, q, qd);
    const bool g = det.update(q, qd, tau, kT, plant.twist_to_joint(q));
    if (g != last) ++out.switches;
    last = g;
    out.tip_travel = std::max(out.tip_travel, (plant.forward_kinematics(q).x - x0).norm());
    if (k >= n / 2) {
      s0 += det.estimate_released().head<3>().squaredNorm();
      s1 += det.estimate_gripped().head<3>().squaredNorm();
      ++m;
    }
  }
  out.gripped = det.gripped();
  out.statistic = det.statistic();
  out.rms_h0 = std::sqrt(s0 / m);
  out.rms_h1 = std::sqrt(s1 / m);
  return out;
}

void report(const char* label, const Outcome& o) {
  std::printf("%s: gripped %d switches %d s %.3g N^2/kg, rms |h0| %.3g N |h1| %.3g N, tip travel "
              "%.2f mm\n",
              label, o.gripped, o.switches, o.statistic, o.rms_h0, o.rms_h1, 1e3 * o.tip_travel);
}

TEST(GripDetector, PlantCarryingTheHandIsJudgedGripped) {
  const PhantomModel base(default_phantom_params());
  const GraspMassModel grasp(base, kMass, kInertia);
  GripDetectorParams prm;
  prm.start_gripped = false;
  GripDetector det(grasp, VecX::Constant(6, 200.0), {}, prm);
  const Outcome o = drive(grasp, det, 0.08, 6.0, 1.0);
  report("hand on", o);
  EXPECT_TRUE(o.gripped);
  EXPECT_EQ(o.switches, 1);
  EXPECT_LT(o.statistic, -prm.grip_threshold);
  // H1 is the plant: its estimate is the observer's discretisation error only; H0 reports the
  // hand's inertial reaction -m_h a as human force.
  EXPECT_GT(o.rms_h0, 0.1);
  EXPECT_LT(o.rms_h1, 0.01 * o.rms_h0);
  EXPECT_LT(o.tip_travel, 0.02);  // stayed a small motion about the centre of the workspace
}

TEST(GripDetector, PlantWithoutTheHandIsJudgedReleased) {
  const PhantomModel base(default_phantom_params());
  const GraspMassModel grasp(base, kMass, kInertia);
  GripDetector det(grasp, VecX::Constant(6, 200.0), {});
  ASSERT_TRUE(det.gripped());
  const Outcome o = drive(base, det, 0.04, 6.0, 1.0);
  report("hand off", o);
  EXPECT_FALSE(o.gripped);
  EXPECT_EQ(o.switches, 1);
  EXPECT_GT(o.statistic, det.params().release_threshold);
  EXPECT_GT(o.rms_h1, 0.1);
  EXPECT_LT(o.rms_h0, 0.01 * o.rms_h1);
  EXPECT_EQ(&det.model(), static_cast<const SixDofDeviceModel*>(&base));
}

TEST(GripDetector, AtRestTheStatisticIsZeroAndNothingSwitches) {
  const PhantomModel base(default_phantom_params());
  const GraspMassModel grasp(base, kMass, kInertia);
  for (const bool start : {true, false}) {
    GripDetectorParams prm;
    prm.start_gripped = start;
    GripDetector det(grasp, VecX::Constant(6, 200.0), {}, prm);
    const Outcome o = drive(base, det, 0.0, 6.0, 0.3);
    EXPECT_EQ(o.gripped, start);
    EXPECT_EQ(o.switches, 0);
    EXPECT_NEAR(o.statistic, 0.0, 1e-12);
    EXPECT_LT(o.tip_travel, 1e-9);
  }
}

TEST(GripDetector, RejectsBadParameters) {
  const PhantomModel base(default_phantom_params());
  const GraspMassModel grasp(base, kMass, kInertia);
  const GraspMassModel massless(base, 0.0, kInertia);
  const VecX L = VecX::Constant(6, 200.0);
  EXPECT_THROW(GripDetector(massless, L, {}), std::invalid_argument);
  GripDetectorParams band;
  band.lowpass_hz = band.highpass_hz;
  EXPECT_THROW(GripDetector(grasp, L, {}, band), std::invalid_argument);
  GripDetectorParams tau;
  tau.power_time_constant_s = 0.0;
  EXPECT_THROW(GripDetector(grasp, L, {}, tau), std::invalid_argument);
  GripDetectorParams thr;
  thr.release_threshold = -1.0;
  EXPECT_THROW(GripDetector(grasp, L, {}, thr), std::invalid_argument);
  EXPECT_THROW(GripDetector(grasp, VecX::Constant(5, 200.0), {}), std::invalid_argument);
}

}  // namespace
}  // namespace dentsim
