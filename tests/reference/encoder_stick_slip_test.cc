// The encoder Kalman filter's stick-slip prediction (reference/encoder_kalman.h
// encoder_stick_slip_velocity; docs/derivations/quiet_stiffness.md 8.7): the solver against a
// brute-force enumeration of every stick/slip pattern, its impulse never adds kinetic energy, the
// 1-joint stick and slip cases against their closed forms, and the scene key
// method.encoder_kalman_friction_model reaching the pipeline.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <random>
#include <string>

#include "reference/core/io.h"
#include "reference/encoder_kalman.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"
#include "reference/tick.h"
#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {
namespace {

// Every pattern (stick, slip forward, slip backward) per joint with f_c > 0: the sticking joints'
// impulses solved, the sliding ones' at their bound; the feasible pattern's v+ (exactly one for M
// SPD). Returns the number of feasible patterns.
int brute_force(const Mat6& M, const Vec6& b, const Vec6& f_c, const Vec6& v, const Vec6& r,
                double T, Vec6* v_plus) {
  Mat6 A = M;
  A.diagonal() += T * b;
  const Mat6 W = A.inverse();
  const Vec6 v_free = W * (M * v + T * r);
  const Vec6 c = T * f_c;
  int feasible = 0;
  int patterns = 1;
  for (int i = 0; i < 6; ++i) patterns *= 3;
  for (int p = 0; p < patterns; ++p) {
    std::array<int, 6> s{};  // 0 stick, 1 forward (lambda = -c), 2 backward (lambda = +c)
    int code = p;
    bool skip = false;
    for (int i = 0; i < 6; ++i) {
      s[i] = code % 3;
      code /= 3;
      if (!(c(i) > 0.0) && s[i] != 1) skip = true;  // no friction: one pattern (lambda = 0)
    }
    if (skip) continue;
    Mat6 K = Mat6::Identity();
    Vec6 rhs = Vec6::Zero();
    for (int i = 0; i < 6; ++i) {
      if (!(c(i) > 0.0)) continue;
      if (s[i] == 0) {
        K.row(i) = W.row(i);
        rhs(i) = -v_free(i);
      } else {
        rhs(i) = s[i] == 1 ? -c(i) : c(i);
      }
    }
    const Vec6 lambda = K.fullPivLu().solve(rhs);
    const Vec6 w = v_free + W * lambda;
    bool ok = true;
    for (int i = 0; i < 6 && ok; ++i) {
      if (!(c(i) > 0.0)) continue;
      const double tol = 1e-10 * (1.0 + v_free.cwiseAbs().maxCoeff());
      if (s[i] == 0) ok = std::abs(lambda(i)) <= c(i) * (1.0 + 1e-10);
      if (s[i] == 1) ok = w(i) >= -tol;
      if (s[i] == 2) ok = w(i) <= tol;
    }
    if (ok) {
      ++feasible;
      *v_plus = w;
      for (int i = 0; i < 6; ++i) {
        if (c(i) > 0.0 && s[i] == 0) (*v_plus)(i) = 0.0;
      }
    }
  }
  return feasible;
}

// A random SPD inertia with the Phantom's spread: arm joints ~1e-3, gimbal ~1e-5 kg m^2, coupled.
Mat6 random_inertia(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mat6 L = Mat6::Zero();
  const Vec6 scale(3e-2, 3e-2, 3e-2, 3e-3, 3e-3, 3e-3);
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j <= i; ++j) L(i, j) = scale(i) * (i == j ? 1.0 + 0.5 * u(rng) : 0.6 * u(rng));
  }
  return L * L.transpose();
}

TEST(EncoderStickSlip, MatchesTheBruteForceEnumeration) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double T = 1e-3;
  int sticks = 0, slips = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 300; ++trial) {
    const Mat6 M = random_inertia(rng);
    Vec6 b, f_c, v, r;
    for (int i = 0; i < 6; ++i) {
      const double s = i < 3 ? 1.0 : 0.1;
      b(i) = s * 2e-3 * (1.0 + u(rng));
      f_c(i) = trial % 7 == 0 && i == 4 ? 0.0 : s * 5e-3 * (1.0 + u(rng));
      v(i) = 0.3 * u(rng) * (trial % 3 == 0 ? 0.01 : 1.0);  // some near rest
      r(i) = s * 1e-2 * u(rng);
    }
    Vec6 expected = Vec6::Zero(), got = Vec6::Constant(99.0), lambda = Vec6::Zero();
    ASSERT_EQ(brute_force(M, b, f_c, v, r, T, &expected), 1) << "trial " << trial;
    ASSERT_TRUE(encoder_stick_slip_velocity(M, b, f_c, v, r, T, &got, &lambda));
    const double scale = 1e-9 * (1.0 + expected.cwiseAbs().maxCoeff());
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(got(i), expected(i), scale) << "trial " << trial << " joint " << i;
      if (expected(i) == 0.0) {
        EXPECT_EQ(got(i), 0.0) << "a sticking joint predicts no motion, trial " << trial;
        ++sticks;
      } else {
        ++slips;
      }
    }
    worst = std::max(worst, (got - expected).cwiseAbs().maxCoeff());
    // The impulse satisfies the box and M (v+ - v) = T (r - B v+) + lambda.
    for (int i = 0; i < 6; ++i) EXPECT_LE(std::abs(lambda(i)), T * f_c(i) * (1.0 + 1e-12));
    const Vec6 residual = M * (got - v) - T * (r - b.asDiagonal() * got) - lambda;
    EXPECT_LE(residual.cwiseAbs().maxCoeff(), 1e-12);
  }
  std::printf(
      "300 random coupled cases: %d sticking and %d sliding joints, worst |v+ - brute| "
      "%.2e rad/s\n",
      sticks, slips, worst);
  EXPECT_GT(sticks, 100);  // both regimes are exercised
  EXPECT_GT(slips, 100);
}

// The friction impulse never adds kinetic energy: in the metric A = M + T B of the step, with
// v_free the velocity without Coulomb friction, 1/2 v+^T A v+ <= 1/2 v_free^T A v_free, and per
// joint lambda_i v+_i <= 0 (a sticking joint does no work, a sliding one loses f_c T |v+_i|).
TEST(EncoderStickSlip, TheFrictionImpulseNeverAddsKineticEnergy) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double T = 1e-3;
  for (int trial = 0; trial < 200; ++trial) {
    const Mat6 M = random_inertia(rng);
    Vec6 b, f_c, v, r;
    for (int i = 0; i < 6; ++i) {
      b(i) = 1e-3 * (1.0 + u(rng));
      f_c(i) = 4e-3 * (1.0 + u(rng));
      v(i) = 0.5 * u(rng);
      r(i) = 2e-2 * u(rng);
    }
    Mat6 A = M;
    A.diagonal() += T * b;
    const Vec6 v_free = A.llt().solve(M * v + T * r);
    Vec6 w, lambda;
    ASSERT_TRUE(encoder_stick_slip_velocity(M, b, f_c, v, r, T, &w, &lambda));
    const double e_free = 0.5 * v_free.dot(A * v_free), e_plus = 0.5 * w.dot(A * w);
    EXPECT_LE(e_plus, e_free * (1.0 + 1e-12)) << "trial " << trial;
    for (int i = 0; i < 6; ++i) EXPECT_LE(lambda(i) * w(i), 1e-18) << "trial " << trial;
  }
}

// One joint (the others without friction and decoupled): a torque below f_c from rest sticks
// with v+ exactly 0; above it the joint slides with a = (tau - f_c sign(v)) / m (b = 0), and with
// viscous friction v+ = (m v + T (tau - f_c sign)) / (m + T b).
TEST(EncoderStickSlip, OneJointSticksBelowCoulombAndSlidesAbove) {
  const double T = 1e-3, m = 2e-3, f_c = 5e-3;
  Mat6 M = Mat6::Identity();
  M(0, 0) = m;
  Vec6 fc = Vec6::Zero(), b = Vec6::Zero(), v = Vec6::Zero(), r = Vec6::Zero(), w;
  fc(0) = f_c;
  for (const double tau : {0.0, 1e-3, -4.9e-3, 4.999e-3}) {
    r(0) = tau;
    ASSERT_TRUE(encoder_stick_slip_velocity(M, b, fc, v, r, T, &w));
    EXPECT_EQ(w(0), 0.0) << "tau " << tau;  // exactly at rest
  }
  // Moving slowly, a small torque: friction stops it within the tick (no reversal).
  v(0) = 1e-3;
  r(0) = 1e-3;
  ASSERT_TRUE(encoder_stick_slip_velocity(M, b, fc, v, r, T, &w));
  EXPECT_EQ(w(0), 0.0);
  // Sliding: from rest above f_c, and moving against a torque.
  for (const auto& [v0, tau] : {std::pair{0.0, 8e-3}, {0.0, -7e-3}, {0.4, -1e-3}, {-0.3, 2e-2}}) {
    v(0) = v0;
    r(0) = tau;
    ASSERT_TRUE(encoder_stick_slip_velocity(M, b, fc, v, r, T, &w));
    const double sign = v0 != 0.0 ? (v0 > 0.0 ? 1.0 : -1.0) : (tau > 0.0 ? 1.0 : -1.0);
    const double a = (tau - f_c * sign) / m;
    EXPECT_NEAR((w(0) - v0) / T, a, 1e-9 * std::abs(a)) << "v0 " << v0 << " tau " << tau;
  }
  b(0) = 0.4;  // m + T b = 2.4e-3
  v(0) = 0.4;
  r(0) = 1e-3;
  ASSERT_TRUE(encoder_stick_slip_velocity(M, b, fc, v, r, T, &w));
  EXPECT_NEAR(w(0), (m * 0.4 + T * (1e-3 - f_c)) / (m + T * 0.4), 1e-14);
  // The joints without friction move freely: v+ = v + T r / M_ii.
  EXPECT_DOUBLE_EQ(w(1), 0.0);
  r(1) = 0.5;
  ASSERT_TRUE(encoder_stick_slip_velocity(M, b, fc, v, r, T, &w));
  EXPECT_DOUBLE_EQ(w(1), T * 0.5);
  // Bad input: a tick that is not > 0, a non-finite torque.
  EXPECT_FALSE(encoder_stick_slip_velocity(M, b, fc, v, r, 0.0, &w));
  r(2) = NAN;
  EXPECT_FALSE(encoder_stick_slip_velocity(M, b, fc, v, r, T, &w));
}

// The scene key method.encoder_kalman_friction_model reaches the pipeline: "smooth" (default)
// keeps the friction smooth, "stick_slip" sets EncoderKalmanParams::stick_slip, "none" equals
// encoder_kalman_friction false; an unknown value or a contradiction with the old key is refused
// naming the key; the pipeline model takes the device model's coefficients.
TEST(EncoderStickSlip, TheSceneKeyReachesThePipeline) {
  auto params = [](const Scene& s) {
    EncoderKalmanParams seen;
    seen.stick_slip = true;  // overwritten
    seen.model_friction = false;
    SceneRigOptions options;
    options.configure_pipeline = [&](PipelineConfig& pc) { seen = pc.encoder_kalman_params; };
    build_scene_rig(s, options);
    return seen;
  };
  auto patched = [](const std::string& method) {
    return load_scene_patched("probe", nlohmann::json::parse(R"({"method": )" + method + "}"),
                              "test");
  };
  const EncoderKalmanParams def = params(load_scene("probe"));
  EXPECT_TRUE(def.model_friction);
  EXPECT_FALSE(def.stick_slip);
  const EncoderKalmanParams ss =
      params(patched(R"({"encoder_kalman_friction_model": "stick_slip"})"));
  EXPECT_TRUE(ss.model_friction);
  EXPECT_TRUE(ss.stick_slip);
  const EncoderKalmanParams none = params(patched(R"({"encoder_kalman_friction_model": "none"})"));
  EXPECT_FALSE(none.model_friction);
  EXPECT_FALSE(none.stick_slip);
  const EncoderKalmanParams smooth = params(
      patched(R"({"encoder_kalman_friction_model": "smooth", "encoder_kalman_friction": true})"));
  EXPECT_TRUE(smooth.model_friction);
  EXPECT_FALSE(smooth.stick_slip);
  for (const char* bad :
       {R"({"encoder_kalman_friction_model": "coulomb"})",
        R"({"encoder_kalman_friction_model": "stick_slip", "encoder_kalman_friction": false})"}) {
    try {
      patched(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("method.encoder_kalman_friction_model"),
                std::string::npos)
          << e.what();
    }
  }
  // The pipeline model holds the device model's coefficients.
  const PhantomParams pp = default_phantom_params();
  const PhantomModel model(pp);
  PipelineConfig cfg;
  cfg.encoder_kalman = true;
  cfg.encoder_kalman_params.stick_slip = true;
  const ReferencePipeline pipeline(model, cfg);
  EXPECT_EQ(pipeline.model().encoder_friction_b, pp.damping_n_m_s_per_rad);
  EXPECT_EQ(pipeline.model().encoder_friction_fc, pp.coulomb_n_m);
}

}  // namespace
}  // namespace dentsim
