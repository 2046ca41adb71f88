// Dense 6x6 factorisations written out for the fixed size (issue #30: the free-space tick). The
// tick factors three 6x6 matrices: J_t (its inverse J1, (2.2)), the PMI system (4.9) and the
// locked inertia M_L (phi = M_L^-1 E^T M2 E, (3.3)). Eigen's PartialPivLU and LLT of a Mat6 go
// through their generic paths (the blocked LU on a strided reference, and for a matrix right-hand
// side the level-3 triangular solve with its packing): callgrind gave ~12k of a free-space tick's
// 36k instructions to them; 8k of it is saved here (docs/benchmarks.md "Dense 6x6 kernels").
// These are the textbook algorithms with loops of at most six trips. Every loop carries `#pragma
// GCC unroll 6`: without it GCC unrolled only the loops of constant length, not the inner ones
// whose bounds depend on the outer index (k + 1..5, 0..k-1), which stayed loops with their
// counters and branches; unrolled, the pmi-pd free-space tick's three factorisations and solves
// take 1.5 k instructions fewer (docs/benchmarks.md "The tick's own arithmetic"). The order of
// every operation is unchanged, so the results are bitwise those of the loops:
//
//   LU with partial pivoting (Golub & Van Loan, Alg. 3.4.1): for k = 0..5, the row p >= k with
//   the largest |A(p,k)| (the first of equals, as Eigen) is swapped into row k, then
//       A(i,k) <- A(i,k) / A(k,k),   A(i,j) <- A(i,j) - A(i,k) A(k,j)   (i, j > k),
//   so that P A = L U with L unit lower (below the diagonal) and U upper (on and above it).
//   Solve: y = L^-1 P b forward, x = U^-1 y backward, both column-oriented (x_i fixed, then
//   subtracted from the rows above or below it), the order of Eigen's small triangular solves.
//
//   Cholesky A = L L^T (A symmetric positive definite; only its lower triangle is read):
//       L(k,k) = sqrt(A(k,k) - sum_{j<k} L(k,j)^2),
//       L(i,k) = (A(i,k) - sum_{j<k} L(i,j) L(k,j)) / L(k,k)   (i > k);
//   false when a pivot's square is not > 0 (not positive definite, or not finite).
//   Both keep the reciprocals of their pivots: the solves multiply by them (six divisions a
//   factor, not one per row and right-hand side).
//
// They differ from Eigen's factorisations by round-off only (the sums' order);
// tests/fast/dense6_test.cc pins them against Eigen on random, ill-scaled and pivoting
// matrices, and the tick's differential tests (tests/fast/tick_test.cc) against the reference.
// Nothing here allocates or throws.
#pragma once

#include <array>
#include <cmath>

#include "reference/core/types.h"

namespace dentsim::fast {

// P A = L U, packed: lu's strict lower triangle is L (unit diagonal implied), the rest U; row i of
// P A is row perm[i] of A.
struct Lu6 {
  Mat6 lu;
  std::array<int, 6> perm;
  Vec6 inv_u;  // 1 / U(k,k): the solves multiply (a division costs ~10 multiplications)
};

// Factors A; false when a pivot is zero or the matrix is not finite (the factor is then
// meaningless). Whether the system is well conditioned is the caller's test (on U's diagonal).
inline bool lu6(const Mat6& A, Lu6* f) {
  Mat6& a = f->lu;
  a = A;
  #pragma GCC unroll 6
  for (int i = 0; i < 6; ++i) f->perm[i] = i;
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) {
    int p = k;
    double best = std::abs(a(k, k));
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) {
      const double v = std::abs(a(i, k));
      if (v > best) {
        best = v;
        p = i;
      }
    }
    if (!(best > 0.0) || !std::isfinite(best)) return false;
    if (p != k) {
      #pragma GCC unroll 6
      for (int j = 0; j < 6; ++j) std::swap(a(k, j), a(p, j));
      std::swap(f->perm[k], f->perm[p]);
    }
    const double inv = 1.0 / a(k, k);
    f->inv_u[k] = inv;
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) a(i, k) *= inv;
    #pragma GCC unroll 6
    for (int j = k + 1; j < 6; ++j) {
      const double akj = a(k, j);
      #pragma GCC unroll 6
      for (int i = k + 1; i < 6; ++i) a(i, j) -= a(i, k) * akj;
    }
  }
  return true;
}

// x = A^-1 b from the factor (x may not alias b).
inline void lu6_solve(const Lu6& f, const Vec6& b, Vec6* x) {
  const Mat6& a = f.lu;
  Vec6& y = *x;
  #pragma GCC unroll 6
  for (int i = 0; i < 6; ++i) y[i] = b[f.perm[i]];
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) {  // L y = P b, L unit lower
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) y[i] -= a(i, k) * y[k];
  }
  #pragma GCC unroll 6
  for (int k = 5; k >= 0; --k) {  // U x = y
    y[k] *= f.inv_u[k];
    #pragma GCC unroll 6
    for (int i = 0; i < k; ++i) y[i] -= a(i, k) * y[k];
  }
}

// A^-1 from the factor: the six right-hand sides e_j solved side by side, a row of all six at a
// time (row operations on a row-major local, which Eigen vectorises; the local cannot alias the
// factor, so the loops keep it in registers).
inline void lu6_inverse(const Lu6& f, Mat6* inv) {
  const Mat6& a = f.lu;
  using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  RowMajor6 x = RowMajor6::Zero();
  #pragma GCC unroll 6
  for (int i = 0; i < 6; ++i) x(i, f.perm[i]) = 1.0;  // P
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) {  // L Y = P
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) x.row(i) -= a(i, k) * x.row(k);
  }
  #pragma GCC unroll 6
  for (int k = 5; k >= 0; --k) {  // U X = Y
    x.row(k) *= f.inv_u[k];
    #pragma GCC unroll 6
    for (int i = 0; i < k; ++i) x.row(i) -= a(i, k) * x.row(k);
  }
  *inv = x;
}

// A = L L^T, with 1 / L(k,k) kept for the solves; L's strict upper triangle is zero.
struct Llt6 {
  Mat6 l;
  Vec6 inv_diag;
};

// False when A is not positive definite (or not finite).
inline bool cholesky6(const Mat6& A, Llt6* f) {
  Mat6& l = f->l;
  l.setZero();
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) {
    double s = A(k, k);
    #pragma GCC unroll 6
    for (int j = 0; j < k; ++j) s -= l(k, j) * l(k, j);
    if (!(s > 0.0) || !std::isfinite(s)) return false;
    const double lkk = std::sqrt(s);
    const double inv = 1.0 / lkk;
    l(k, k) = lkk;
    f->inv_diag[k] = inv;
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) {
      double t = A(i, k);
      #pragma GCC unroll 6
      for (int j = 0; j < k; ++j) t -= l(i, j) * l(k, j);
      l(i, k) = t * inv;
    }
  }
  return true;
}

// x = A^-1 b from A's factor (L y = b forward, L^T x = y backward; x may alias b).
inline void cholesky6_solve(const Llt6& f, const Vec6& b, Vec6* x) {
  const Mat6& l = f.l;
  Vec6 y = b;
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) {
    y[k] *= f.inv_diag[k];
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) y[i] -= l(i, k) * y[k];
  }
  #pragma GCC unroll 6
  for (int k = 5; k >= 0; --k) {
    #pragma GCC unroll 6
    for (int j = k + 1; j < 6; ++j) y[k] -= l(j, k) * y[j];
    y[k] *= f.inv_diag[k];
  }
  *x = y;
}

// B <- A^-1 B from A's factor (L Y = B forward, L^T X = Y backward), a row of all six right-hand
// sides at a time on a row-major local, as lu6_inverse.
inline void cholesky6_solve_in_place(const Llt6& f, Mat6* B) {
  const Mat6& l = f.l;
  Eigen::Matrix<double, 6, 6, Eigen::RowMajor> x = *B;
  #pragma GCC unroll 6
  for (int k = 0; k < 6; ++k) {
    x.row(k) *= f.inv_diag[k];
    #pragma GCC unroll 6
    for (int i = k + 1; i < 6; ++i) x.row(i) -= l(i, k) * x.row(k);
  }
  #pragma GCC unroll 6
  for (int k = 5; k >= 0; --k) {
    #pragma GCC unroll 6
    for (int j = k + 1; j < 6; ++j) x.row(k) -= l(j, k) * x.row(j);
    x.row(k) *= f.inv_diag[k];
  }
  *B = x;
}

}  // namespace dentsim::fast
