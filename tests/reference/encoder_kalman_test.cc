// The encoder Kalman filter (reference/encoder_kalman.h; issue #29 item 3): Kalata's closed-form
// gains against the iterated Riccati equation, the estimate never leaves the encoder cell and
// beats the cell centre and the driver's backward difference on a quantised trajectory whose
// acceleration the model knows, and the fast pipeline equals the reference tick for tick with the
// filter on (the stage is shared: fast::device_terms calls the reference's); the prediction does
// not use the model's joint friction (docs/derivations/quiet_stiffness.md 8.6).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "device/closed_loop.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "reference/encoder_kalman.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"
#include "reference/tick.h"

namespace dentsim {
namespace {

TEST(EncoderKalman, KalataGainsAreTheSteadyStateKalmanGains) {
  const double T = 1e-3, sigma_m = 1.0;
  for (const double lambda : {1e-4, 8.3e-3, 0.1, 1.0, 5.0}) {
    const double sigma_a = lambda * sigma_m / (T * T);
    Eigen::Matrix2d F;
    F << 1.0, T, 0.0, 1.0;
    const Eigen::Vector2d G(0.5 * T * T, T);
    const Eigen::Matrix2d Q = G * G.transpose() * sigma_a * sigma_a;
    Eigen::Matrix2d P = Eigen::Matrix2d::Identity();
    Eigen::Vector2d K = Eigen::Vector2d::Zero();
    for (int k = 0; k < 200000; ++k) {
      P = F * P * F.transpose() + Q;
      K = P.col(0) / (P(0, 0) + sigma_m * sigma_m);
      P = P - K * P.row(0);
    }
    double alpha = 0.0, beta = 0.0;
    alpha_beta_gains(lambda, &alpha, &beta);
    EXPECT_NEAR(alpha, K(0), 1e-9 * K(0)) << lambda;
    EXPECT_NEAR(beta, K(1) * T, 1e-9 * K(1) * T) << lambda;
  }
}

// One joint moving q(t) = A sin(w t) (a = -w^2 q known to the filter), read by a floor encoder.
TEST(EncoderKalman, EstimateStaysInTheCellAndBeatsTheCountAndTheBackwardDifference) {
  const double T = 1e-3, delta = 1.0e-4, A = 2e-3, w = 2.0 * M_PI * 2.0;
  Vec6 quantum = Vec6::Zero();
  quantum(0) = delta;
  Vec6 sigma_a = Vec6::Zero();
  sigma_a(0) = 1.0;  // [rad/s^2]: an unknown torque the filter allows for
  EncoderKalmanState s;
  auto meas = [&](double t) { return delta * std::floor(A * std::sin(w * t) / delta); };
  Vec6 q_m = Vec6::Zero(), qd_m = Vec6::Zero();
  q_m(0) = meas(0.0);
  encoder_kalman_reset(q_m, qd_m, quantum, s);
  double e_filter = 0.0, e_cell = 0.0, ev_filter = 0.0, ev_diff = 0.0;
  long n = 0;
  double q_prev = q_m(0);
  for (int k = 1; k <= 4000; ++k) {
    const double t = k * T;
    q_m(0) = meas(t);
    Vec6 accel = Vec6::Zero();
    accel(0) = -w * w * A * std::sin(w * (t - T));  // over the tick that just ended
    encoder_kalman_update(q_m, qd_m, quantum, accel, sigma_a, T, s);
    ASSERT_GE(s.q(0), q_m(0));
    ASSERT_LE(s.q(0), q_m(0) + delta);
    const double q_true = A * std::sin(w * t), v_true = A * w * std::cos(w * t);
    if (k > 500) {
      e_filter += std::pow(s.q(0) - q_true, 2);
      e_cell += std::pow(q_m(0) + 0.5 * delta - q_true, 2);
      ev_filter += std::pow(s.qd(0) - v_true, 2);
      ev_diff += std::pow((q_m(0) - q_prev) / T - v_true, 2);
      ++n;
    }
    q_prev = q_m(0);
  }
  const double rms_filter = std::sqrt(e_filter / n), rms_cell = std::sqrt(e_cell / n);
  const double rmsv_filter = std::sqrt(ev_filter / n), rmsv_diff = std::sqrt(ev_diff / n);
  std::printf("position rms: filter %.3e, cell centre %.3e (Delta/sqrt(12) = %.3e) rad\n",
              rms_filter, rms_cell, delta / std::sqrt(12.0));
  std::printf("velocity rms: filter %.3e, backward difference %.3e rad/s\n", rmsv_filter, rmsv_diff);
  EXPECT_LT(rms_filter, 0.7 * rms_cell);
  EXPECT_LT(rmsv_filter, 0.1 * rmsv_diff);
  // Joints without a quantum pass the measurement through.
  EXPECT_EQ(s.q(1), q_m(1));
  EXPECT_EQ(s.qd(1), qd_m(1));
}

// The probe scene with the filter on: the fast pipeline equals the reference in free space (the
// contact stage's round-off differs by design afterwards: tests/fast/tick_test.cc), and the filter
// changes the torque (it is on).
TEST(EncoderKalman, FastPipelineEqualsTheReferenceWithTheFilterOn) {
  Scene scene = load_scene("probe");
  auto torques = [&](const std::string& pipeline, bool on) {
    Scene s = scene;
    s.method.encoder_kalman = on;
    SceneRigOptions options;
    options.pipeline = pipeline;
    const std::unique_ptr<SceneRig> rig = build_scene_rig(s, options);
    rig->loop->start();
    std::vector<VecX> out;
    for (int k = 0; k < 700; ++k) {  // 0.7 s of the approach, in free space (contact at 0.76 s)
      const TickResult& r = rig->loop->step();
      EXPECT_TRUE(r.contacts.empty());
      out.push_back(r.tau);
    }
    EXPECT_FALSE(rig->loop->faulted());
    return out;
  };
  const auto ref = torques("reference", true);
  const auto fast = torques("fast", true);
  const auto off = torques("reference", false);
  double max_diff = 0.0, max_tau = 0.0, max_change = 0.0;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    max_diff = std::max(max_diff, (ref[k] - fast[k]).cwiseAbs().maxCoeff());
    max_tau = std::max(max_tau, ref[k].cwiseAbs().maxCoeff());
    max_change = std::max(max_change, (ref[k] - off[k]).cwiseAbs().maxCoeff());
  }
  std::printf("fast vs reference: max torque diff %.3e N m (largest %.3e), filter on vs off %.3e\n",
              max_diff, max_tau, max_change);
  EXPECT_LE(max_diff, 1e-9 * max_tau);
  EXPECT_GT(max_change, 1e-3 * max_tau);
}


// EncoderKalmanParams::model_friction = false (scene key method.encoder_kalman_friction) leaves the
// joints' friction to the process noise (a haptic standstill's Coulomb friction is set-valued, not
// the smooth f_c tanh(qd_hat / v_s) of the filter's own velocity, whose slope made the Phantom's
// gimbal hunt: quiet_stiffness.md 8.6). The device_terms stage on the same quantised samples and
// applied torque, with two device models that differ only in their Coulomb friction (the
// Phantom's and 20 times it): without the model's friction the estimates are identical; with it
// (the default) they differ, as the models' friction terms do.
TEST(EncoderKalman, WithoutModelFrictionThePredictionIgnoresTheFriction) {
  const PhantomParams base = default_phantom_params();
  PhantomParams rough = base;
  rough.coulomb_n_m = 20.0 * base.coulomb_n_m;
  ASSERT_GT(base.coulomb_n_m.minCoeff(), 0.0);
  const PhantomModel model_a(base), model_b(rough);
  auto run = [&](bool model_friction, double* friction_diff) {
    PipelineConfig cfg;
    cfg.encoder_kalman = true;
    cfg.encoder_kalman_params.model_friction = model_friction;
    cfg.encoder_quantum = VecX(6);
    for (int i = 0; i < 6; ++i) {
      cfg.encoder_quantum(i) = 2.0 * M_PI / base.encoder_counts_per_rev(i);
    }
    ReferencePipeline pa(model_a, cfg), pb(model_b, cfg);
    PipelineData da = pa.data(), db = pb.data();
    const Vec6 q0(0.0, 0.35, 0.3, 0.0, 0.0, 0.0);
    const Vec6 tau(0.01, -0.02, 0.015, 1e-3, -1e-3, 5e-4);
    double max_diff = 0.0, max_move = 0.0;
    *friction_diff = 0.0;
    Vec6 q_prev = q0;
    for (int k = 0; k <= 400; ++k) {
      const double t = 1e-3 * k;
      // A slow back-and-forth through zero velocity, as at a press: 2 Hz, 5 counts per joint.
      Vec6 q_meas;
      for (int i = 0; i < 6; ++i) {
        const double d = cfg.encoder_quantum(i);
        q_meas(i) = d * std::floor((q0(i) + 5.0 * d * std::sin(4.0 * M_PI * t)) / d);
      }
      for (PipelineData* d : {&da, &db}) {
        d->q = q_meas;
        d->qd = (q_meas - q_prev) / 1e-3;
        d->t = t;
        d->T = 1e-3;
        d->tau_prev = tau;
      }
      q_prev = q_meas;
      EXPECT_EQ(reference::device_terms(pa.model(), da), TickStatus::kOk);
      EXPECT_EQ(reference::device_terms(pb.model(), db), TickStatus::kOk);
      max_diff = std::max({max_diff, (da.q - db.q).cwiseAbs().maxCoeff(),
                           (da.qd - db.qd).cwiseAbs().maxCoeff()});
      *friction_diff = std::max(*friction_diff, (da.dev.tau_f - db.dev.tau_f).norm());
      max_move = std::max(max_move, (da.q - q0).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(max_move, 2.0 * cfg.encoder_quantum(3));  // the estimate moves
    return max_diff;
  };
  double friction_off = 0.0, friction_on = 0.0;
  const double diff_off = run(false, &friction_off);
  const double diff_on = run(true, &friction_on);
  std::printf("estimate difference: %.3e without the model's friction, %.3e with it "
              "(friction terms differ by %.3e / %.3e N m)\n",
              diff_off, diff_on, friction_off, friction_on);
  EXPECT_EQ(diff_off, 0.0);
  EXPECT_GT(friction_off, 10.0 * base.coulomb_n_m(0));  // the models do differ
  EXPECT_GT(diff_on, 1e-3);                             // and the default uses it
}

// The scene key method.encoder_kalman_friction reaches the pipeline (default true).
TEST(EncoderKalman, TheSceneKeySetsTheModelFriction) {
  auto model_friction = [](const Scene& s) {
    bool seen = true;
    SceneRigOptions options;
    options.configure_pipeline = [&](PipelineConfig& pc) {
      seen = pc.encoder_kalman_params.model_friction;
    };
    build_scene_rig(s, options);
    return seen;
  };
  EXPECT_TRUE(load_scene("probe").method.encoder_kalman_friction);
  EXPECT_TRUE(model_friction(load_scene("probe")));
  const Scene off = load_scene_patched(
      "probe", nlohmann::json::parse(R"({"method": {"encoder_kalman_friction": false}})"), "test");
  EXPECT_FALSE(off.method.encoder_kalman_friction);
  EXPECT_FALSE(model_friction(off));
}

}  // namespace
}  // namespace dentsim
