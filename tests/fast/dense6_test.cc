// fast/dense6.h against Eigen's factorisations (the reference's): the LU with partial pivoting
// (solve, inverse, the pivots it picks), the Cholesky factor and its matrix solve, on random,
// badly scaled and pivot-forcing matrices, and the refusals (singular, not positive definite,
// not finite).
#include "fast/dense6.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <random>

namespace dentsim::fast {
namespace {

Mat6 random_matrix(std::mt19937& rng, double scale_spread) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> e(-scale_spread, scale_spread);
  Mat6 a;
  for (int j = 0; j < 6; ++j) {
    for (int i = 0; i < 6; ++i) a(i, j) = u(rng);
  }
  // Rows and columns scaled over 10^(+-scale_spread), as the PMI system's and J_t's are (metres
  // against radians, grams against kg m^2).
  for (int i = 0; i < 6; ++i) {
    a.row(i) *= std::pow(10.0, e(rng));
    a.col(i) *= std::pow(10.0, e(rng));
  }
  return a;
}

Mat6 random_spd(std::mt19937& rng, double scale_spread) {
  const Mat6 b = random_matrix(rng, scale_spread);
  Mat6 a = b * b.transpose();
  a.diagonal().array() += 1e-3 * a.diagonal().maxCoeff();
  return a;
}

double relative(const Mat6& x, const Mat6& ref) { return (x - ref).norm() / ref.norm(); }
double relative(const Vec6& x, const Vec6& ref) { return (x - ref).norm() / ref.norm(); }

TEST(Dense6, LuSolveAndInverseEqualEigensToRoundOff) {
  std::mt19937 rng(7);
  double worst_solve = 0.0, worst_inverse = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const Mat6 A = random_matrix(rng, trial < 250 ? 0.0 : 2.0);
    const Vec6 b = Vec6::Random();
    const Eigen::PartialPivLU<Mat6> ref(A);
    Lu6 lu;
    ASSERT_TRUE(lu6(A, &lu));
    // The same pivots (the largest, the first of equals), so the same packed factor: a different
    // pivot would change it at O(1).
    EXPECT_LE(relative(lu.lu, ref.matrixLU()), 1e-13) << trial;
    Vec6 x;
    lu6_solve(lu, b, &x);
    const Vec6 x_ref = ref.solve(b);
    Mat6 inv;
    lu6_inverse(lu, &inv);
    const double cond = A.norm() * ref.inverse().norm();
    worst_solve = std::max(worst_solve, relative(x, x_ref) / cond);
    worst_inverse = std::max(worst_inverse, relative(inv, ref.inverse()) / cond);
  }
  // Backward stable both: the difference is round-off times the condition number.
  EXPECT_LE(worst_solve, 1e-14);
  EXPECT_LE(worst_inverse, 1e-14);
}

TEST(Dense6, LuPivotsAZeroDiagonalAndSolvesExactly) {
  // A permutation of a diagonal matrix: every leading entry is zero, so each step must pivot; the
  // solve is then exact (divisions by powers of two).
  Mat6 A = Mat6::Zero();
  const int to[6] = {3, 0, 5, 1, 4, 2};
  for (int j = 0; j < 6; ++j) A(to[j], j) = std::ldexp(1.0, j - 2);
  Lu6 lu;
  ASSERT_TRUE(lu6(A, &lu));
  Vec6 b;
  b << 1.0, 2.0, 3.0, 4.0, 5.0, 6.0;
  Vec6 x;
  lu6_solve(lu, b, &x);
  for (int j = 0; j < 6; ++j) EXPECT_EQ(x[j], b[to[j]] / std::ldexp(1.0, j - 2)) << j;
  Mat6 inv;
  lu6_inverse(lu, &inv);
  EXPECT_EQ(inv * A, Mat6::Identity());
}

TEST(Dense6, LuRefusesASingularOrNonFiniteMatrix) {
  Mat6 A = Mat6::Identity();
  A.col(4).setZero();
  Lu6 lu;
  EXPECT_FALSE(lu6(A, &lu));
  A = Mat6::Identity();
  A(2, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(lu6(A, &lu));
  A = Mat6::Identity();
  A(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(lu6(A, &lu));
}

TEST(Dense6, CholeskySolveEqualsEigensToRoundOff) {
  std::mt19937 rng(11);
  double worst_factor = 0.0, worst_solve = 0.0, worst_vector = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const Mat6 A = random_spd(rng, trial < 250 ? 0.0 : 1.5);
    const Eigen::LLT<Mat6> ref(A);
    ASSERT_EQ(ref.info(), Eigen::Success);
    Llt6 L;
    ASSERT_TRUE(cholesky6(A, &L));
    EXPECT_TRUE(L.l.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().isZero(0.0));
    worst_factor = std::max(worst_factor, relative(L.l, Mat6(ref.matrixL())));
    const Mat6 B = random_matrix(rng, 0.0);
    Mat6 X = B;
    cholesky6_solve_in_place(L, &X);
    const double cond = A.norm() * ref.solve(Mat6::Identity()).norm();
    worst_solve = std::max(worst_solve, relative(X, Mat6(ref.solve(B))) / cond);
    // The vector solve (the device inertia's, fast/tick.cc): the same forward and backward
    // substitutions on one column, so equal to the matrix solve's column bitwise.
    Vec6 x;
    cholesky6_solve(L, B.col(2), &x);
    EXPECT_EQ(x, X.col(2)) << trial;
    worst_vector = std::max(worst_vector, relative(x, Vec6(ref.solve(B.col(2)))) / cond);
  }
  EXPECT_LE(worst_factor, 1e-12);
  EXPECT_LE(worst_solve, 1e-14);
  EXPECT_LE(worst_vector, 1e-14);
}

TEST(Dense6, CholeskyOfADiagonalMatrixIsExact) {
  Vec6 dg;
  dg << 4.0, 0.0625, 0.25, 16.0, 1.0, 64.0;  // powers of 4: every step exact
  Llt6 L;
  ASSERT_TRUE(cholesky6(Mat6(dg.asDiagonal()), &L));
  EXPECT_EQ(L.l, Mat6(dg.cwiseSqrt().asDiagonal()));
  Mat6 X = Mat6::Identity();
  cholesky6_solve_in_place(L, &X);
  EXPECT_EQ(X, Mat6(dg.cwiseInverse().asDiagonal()));
  Vec6 x;
  cholesky6_solve(L, dg, &x);
  EXPECT_EQ(x, Vec6::Ones());
}

TEST(Dense6, CholeskyRefusesWhatIsNotPositiveDefinite) {
  Llt6 L;
  Mat6 A = Mat6::Identity();
  A(3, 3) = -1e-9;
  EXPECT_FALSE(cholesky6(A, &L));
  A = Mat6::Identity();
  A(5, 5) = 0.0;
  EXPECT_FALSE(cholesky6(A, &L));
  A = Mat6::Identity();
  A(1, 0) = A(0, 1) = 1.0;  // singular 2x2 block
  EXPECT_FALSE(cholesky6(A, &L));
  A = Mat6::Identity();
  A(4, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(cholesky6(A, &L));
}

}  // namespace
}  // namespace dentsim::fast
