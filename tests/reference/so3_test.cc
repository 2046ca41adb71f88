// Tests for reference/core/so3.h (part 1 of the reference pipeline).
#include "reference/core/so3.h"
#include "tests/support/random.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>

namespace dentsim {
namespace {

constexpr double kPi = std::numbers::pi;

using testing::random_unit;

TEST(So3, SkewIsCrossProductAndVeeInvertsIt) {
  const Vec3 a(0.3, -1.2, 2.5), b(-0.7, 0.4, 1.1);
  EXPECT_LT((skew(a) * b - a.cross(b)).norm(), 1e-15);
  EXPECT_LT((vee(skew(a)) - a).norm(), 1e-15);
  EXPECT_LT((skew(a) + skew(a).transpose()).norm(), 0.0 + 1e-300);
}

TEST(So3, ExpIsARotationAndMatchesAngleAxis) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ang(0.0, kPi);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 axis = random_unit(rng);
    const double th = ang(rng);
    const Mat3 R = exp_so3(th * axis);
    EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
    const Mat3 expected = Eigen::AngleAxisd(th, axis).toRotationMatrix();
    EXPECT_LT((R - expected).norm(), 1e-14);
  }
}

TEST(So3, LogInvertsExpIncludingSmallAngles) {
  std::mt19937 rng(2);
  for (double th : {0.0, 1e-12, 1e-8, 1e-5, 1e-4, 1.1e-4, 0.1, 1.0, 2.0, 3.0}) {
    for (int i = 0; i < 50; ++i) {
      const Vec3 w = th * random_unit(rng);
      const Vec3 w2 = log_so3(exp_so3(w));
      EXPECT_LT((w2 - w).norm(), 1e-12 * std::max(1.0, th)) << "theta " << th;
    }
  }
}

TEST(So3, LogNearPiIsFiniteAndCorrect) {
  std::mt19937 rng(3);
  for (double eps : {1e-2, 1e-3, 1e-5, 1e-8, 1e-11, 0.0}) {
    for (int i = 0; i < 100; ++i) {
      const Vec3 axis = random_unit(rng);
      const double th = kPi - eps;
      const Mat3 R = exp_so3(th * axis);
      const Vec3 w = log_so3(R);
      ASSERT_TRUE(w.allFinite());
      EXPECT_NEAR(w.norm(), th, 1e-7);
      // The recovered rotation is the same rotation (the axis sign is free at exactly pi).
      EXPECT_LT((exp_so3(w) - R).norm(), 1e-7) << "eps " << eps;
      if (eps >= 1e-5) {
        EXPECT_LT((w - th * axis).norm(), 1e-6) << "eps " << eps;
      }
    }
  }
}

TEST(So3, RotationAngleAccurateAtBothEnds) {
  const Vec3 a = Vec3(1, 2, 3).normalized();
  for (double th : {0.0, 1e-10, 1e-6, 0.5, kPi - 1e-6, kPi}) {
    EXPECT_NEAR(rotation_angle(exp_so3(th * a)), th, 1e-9) << th;
  }
  // acos would lose half the digits at 1e-10; atan2 keeps them.
  EXPECT_NEAR(rotation_angle(exp_so3(1e-10 * a)) / 1e-10, 1.0, 1e-6);
}

TEST(So3, HalfAngleOverSinLimits) {
  EXPECT_DOUBLE_EQ(half_angle_over_sin(0.0), 0.5);
  EXPECT_NEAR(half_angle_over_sin(1e-3), 1e-3 / (2 * std::sin(1e-3)), 1e-15);
  EXPECT_NEAR(half_angle_over_sin(1.0), 1.0 / (2 * std::sin(1.0)), 1e-15);
  EXPECT_TRUE(std::isfinite(half_angle_over_sin(kPi)));
}

TEST(So3, SpringVectorEqualsLogEverywhere) {
  std::mt19937 rng(4);
  for (double th : {0.0, 1e-9, 1e-3, 1.0, 3.0, kPi - 1e-4, kPi - 1e-9}) {
    const Vec3 axis = random_unit(rng);
    const Mat3 R = exp_so3(th * axis);
    const Vec3 s = so3_spring_vector(R);
    ASSERT_TRUE(s.allFinite());
    EXPECT_LT((s - th * axis).norm(), 1e-6) << th;
  }
}

TEST(So3, OrthonormalizeRemovesDrift) {
  Mat3 R = exp_so3(Vec3(0.3, -0.2, 0.9));
  Mat3 drifted = R + 1e-6 * Mat3::Random();
  const Mat3 Q = orthonormalize(drifted);
  EXPECT_LT((Q.transpose() * Q - Mat3::Identity()).norm(), 1e-14);
  EXPECT_LT((Q - R).norm(), 1e-5);
}

}  // namespace
}  // namespace dentsim
