// Loop-lag compensation (reference/lag_compensation.h; issue #29 item 3): the lag it adds is the
// driver's estimate's exact lag on a motion of constant acceleration plus the zero-order hold's
// half tick, so the compensated velocity is the velocity at the midpoint of the tick the command
// is held over; the pipeline uses it only for the coupling and D_d; the fast pipeline equals the
// reference stage by stage with it on (validation/crosscheck_fast.h, the "+lag" configurations).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "device/closed_loop.h"
#include "device/device.h"
#include "device/velocity_estimator.h"
#include "fast/registry.h"
#include "reference/lag_compensation.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "tests/support/crosscheck_rows.h"
#include "validation/crosscheck_fast.h"

namespace dentsim {
namespace {

// q(t) = a t^2 / 2 read by the driver's estimator: estimate + lag a is the true velocity at the
// sample, and + the hold's T/2 the velocity at the midpoint of the coming tick, to round-off.
TEST(LagCompensation, TheLagIsTheEstimatorsExactLagOnConstantAcceleration) {
  const double a = 3.7;  // [rad/s^2]
  for (const double T : {1e-3, 2.5e-4}) {
    for (const double fc : {0.0, 50.0, 200.0, 1000.0}) {
      VelocityEstimatorParams p;
      p.filter = fc > 0.0 ? VelocityFilter::kFirstOrderLowPass : VelocityFilter::kBackwardDifference;
      if (fc > 0.0) p.cutoff_hz = fc;
      VelocityEstimator est(1, p);
      VecX q = VecX::Zero(1);
      est.reset(q, 0.0, VecX::Zero(1));
      ObserverInput in;
      in.match_backward_difference = true;
      in.lowpass_hz = fc;
      const double lag = velocity_estimate_lag(in, T);
      const double loop = loop_velocity_lag(in, T, T);
      EXPECT_DOUBLE_EQ(loop, lag + 0.5 * T);
      if (fc > 0.0) {
        // ~1 / (2 pi f_c) + T/2 when f_c T << 1; the discrete filter lags less than that.
        EXPECT_LT(lag, 0.5 * T + 1.0 / (2.0 * M_PI * fc));
        EXPECT_GT(lag, 0.5 * T + 1.0 / (2.0 * M_PI * fc) - 0.5 * T);
      } else {
        EXPECT_DOUBLE_EQ(lag, 0.5 * T);
      }
      double worst = 0.0;
      const int n = static_cast<int>(std::lround(0.2 / T));
      for (int k = 1; k <= n; ++k) {
        const double t = k * T;
        q(0) = 0.5 * a * t * t;
        const double qd = est.update(q, t)(0);
        if (k > n / 2) {  // the start-up transient (1 - a_f)^k has decayed
          worst = std::max(worst, std::abs(qd + lag * a - a * t));
          worst = std::max(worst, std::abs(qd + loop * a - a * (t + 0.5 * T)));
        }
      }
      std::printf("T %.2e s, f_c %6.0f Hz: lag %.4f ticks, worst error %.2e rad/s\n", T, fc,
                  lag / T, worst);
      EXPECT_LT(worst, 1e-9 * a * n * T) << T << " " << fc;
    }
  }
  // A measured velocity, or the encoder Kalman filter's estimate: only the hold's half tick.
  EXPECT_EQ(velocity_estimate_lag(ObserverInput{}, 1e-3), 0.0);
  EXPECT_DOUBLE_EQ(loop_velocity_lag(ObserverInput{}, 1e-3, 2e-3), 1e-3);
}

// The simulated Phantom's driver is a backward difference low-passed at 200 Hz: the scene rig
// describes it to the pipeline (device/device.h matched_observer_input), and the coupling and D_d
// see V1 = J_t (qd + lag a) while the observer keeps the measured qd.
TEST(LagCompensation, TheRigDescribesTheDriversEstimate) {
  Scene scene = load_scene("probe");
  scene.method.lag_compensation = true;
  scene.method.encoder_kalman = false;  // the driver's estimate (the built-ins have the filter on)
  const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, SceneRigOptions{});
  const auto& staged = dynamic_cast<const StagedPipeline&>(*rig->pipeline);
  EXPECT_TRUE(staged.model().lag_compensation);
  EXPECT_TRUE(staged.model().velocity_estimate.match_backward_difference);
  EXPECT_EQ(staged.model().velocity_estimate.lowpass_hz, 200.0);
  scene.method.encoder_kalman = true;  // its estimate has no difference or low-pass lag
  const std::unique_ptr<SceneRig> rig_k = build_scene_rig(scene, SceneRigOptions{});
  const auto& staged_k = dynamic_cast<const StagedPipeline&>(*rig_k->pipeline);
  EXPECT_FALSE(staged_k.model().velocity_estimate.match_backward_difference);
  EXPECT_EQ(staged_k.model().velocity_estimate.lowpass_hz, 0.0);
}

TEST(LagCompensation, ABadEstimateDescriptionIsRefused) {
  Scene scene = load_scene("probe");
  scene.method.lag_compensation = true;
  SceneRigOptions o;
  o.configure_pipeline = [](PipelineConfig& pc) { pc.velocity_estimate.lowpass_hz = NAN; };
  EXPECT_THROW(build_scene_rig(scene, o), std::invalid_argument);
}

// Stage by stage, in contact, on the probe and the groove (both contact models): the fast
// pipeline equals the reference with the compensation on, within the crosscheck's bound (1e-10
// relative), and the compensation changes the torque (it is on).
TEST(LagCompensation, FastPipelineEqualsTheReferenceWithTheCompensationOn) {
  std::vector<StageConfig> configs;
  for (const char* sc : {"probe", "probe-groove"}) {
    StageConfig c;
    c.scene = sc;
    c.contact_model = std::string(sc) == "probe" ? "sdf" : "faces";
    c.lag_compensation = true;
    configs.push_back(c);
  }
  testing::expect_stage_configs_agree(configs, 1500);
  // On vs off: the same scene's torques differ (in free space already: the hand moves the tool).
  auto torques = [](bool on) {
    Scene s = load_scene("probe");
    s.method.lag_compensation = on;
    const std::unique_ptr<SceneRig> rig = build_scene_rig(s, SceneRigOptions{});
    rig->loop->start();
    std::vector<VecX> out;
    for (int k = 0; k < 700; ++k) out.push_back(rig->loop->step().tau);
    return out;
  };
  const auto on = torques(true), off = torques(false);
  double max_tau = 0.0, max_change = 0.0;
  for (std::size_t k = 0; k < on.size(); ++k) {
    max_tau = std::max(max_tau, off[k].cwiseAbs().maxCoeff());
    max_change = std::max(max_change, (on[k] - off[k]).cwiseAbs().maxCoeff());
  }
  std::printf("compensation on vs off: max torque change %.3e N m (largest %.3e)\n", max_change,
              max_tau);
  EXPECT_GT(max_change, 1e-3 * max_tau);
}

}  // namespace
}  // namespace dentsim
