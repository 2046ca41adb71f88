// Tests for fast/friction.h: every friction solve of the registry (fast/registry.h,
// Implementation::friction) against the reference's (reference/friction.h), on random PMI-like
// cases, on the contact ticks of the built-in scenes (validation/friction_states.h), exactly at
// the stick/slide boundary, without friction, and on zero, NaN, infinite and singular inputs.
//
// The bound (not bitwise: the twins factor A differently and sum in other orders). Both solve, in
// the scaled unknowns y = D^-1 V of the PMI solve (D = diag(1/sqrt|A_ii|), reference/pmi.h):
//   V0 = A^-1 b,  A^-1 H  (backward-stable LU solves of As = D A D: forward error of each
//                          <= c u kappa(As) relative, u = 2^-53),
//   W = H^T A^-1 H,  lambda = -W^-1 H^T V0  (a 2x2 solve: relative error <= c u kappa(Ws) plus
//                          the error of W and H^T V0 it inherits, times kappa(Ws)),
// so the sticking solution (V, lambda, and f_t = [t1 t2] lambda, F = J^T f_t, f_n affine in V)
// differs between two such computations by at most
//   e_stick = c u kappa(As) kappa(Ws),   Ws = (D H)^T As^-1 (D H)  (W in the scaled unknowns),
// relative to the scales below. The scale of lambda's error is not |lambda| but
//   lambda_scale = |lambda| + |Ws^-1| |D H| |y0|
// (the right-hand side H^T V0 cancels when the frictionless slip is small: its error is that of
// V0, times |H|, through W^-1). Sliding adds the scalar s = mu alpha / (1 - mu beta) with
// alpha = f_n(V0), beta = df_n/ds: to first order ds <= (mu |d alpha| + mu s |d beta|) / slope,
// |d alpha| <= e_stick fn_scale, |d beta| <= e_stick |beta|, s <= lambda_scale, hence
//   e_slide = e_stick (1 + mu (fn_scale / lambda_scale + |beta|)) / slope,  slope = 1 - mu beta.
// The scales: |y|_inf of the larger of V and V0 for V; lambda_scale for f_t and, times (1 + |r|)
// (|J^T| <= 1 + |r|), for F; fn_scale = |n^T f0| + |G_f D|_inf |y|_inf for f_n (G_f the force
// rows of the normal wrench's G). c = 10 n with n = 8 (the KKT system's size): the "small factor"
// of the standard bounds (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., Thm 9.4
// and §1.10.1). Measured worst ratios (printed): 0.09 on random cases, 0.10 on the scenes' contact
// ticks, 0.08 at the boundary. A relative error of 1e-9 in any output is far above the bound
// (FrictionTwin.PlantedErrorsFail), and so is a sign flipped in H's torque rows (tried: the
// random, scene, boundary, adversarial and planted-error tests all fail). Seeds fixed and printed.
#include "fast/friction.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "fast/pmi.h"
#include "fast/registry.h"
#include "reference/contact.h"
#include "reference/pmi.h"
#include "tests/fast/bitwise.h"
#include "tests/support/friction_cases.h"
#include "tests/support/stress.h"
#include "validation/friction_states.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;
constexpr double kU = 1.1102230246251565e-16;  // unit round-off 2^-53
constexpr double kC = 80.0;                    // 10 n, n = 8

double kappa(const Eigen::MatrixXd& M) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M);
  const auto& s = svd.singularValues();
  return s(0) / s(s.size() - 1);
}

// The bound of the header for one case, from the reference's quantities recomputed here.
struct Scales {
  bool active = false;
  Vec6 d;                     // the scaling D
  double bound = 0.0;         // e_stick or e_slide
  double lambda_scale = 0.0;  // |lambda| + |Ws^-1| |Hs| |y0|
  double r_norm = 0.0;
  double fn_scale = 0.0;
};

Scales scales(const FrictionState& c, const FrictionSolution& ref) {
  Scales s;
  s.d = pmi_scaling(c.sys.A);
  const Mat6 As = s.d.asDiagonal() * c.sys.A * s.d.asDiagonal();
  const double k_as = kappa(As);
  s.bound = kC * kU * k_as;
  const BlendedContact bc = blended_contact(c.contacts, c.proxy);
  s.active = ref.active;
  if (!ref.active) return s;
  Vec3 t1, t2;
  tangent_basis(bc.n, t1, t2);
  Eigen::Matrix<double, 3, 2> Tt;
  Tt << t1, t2;
  const Eigen::Matrix<double, 6, 2> H = contact_wrench_map(bc.r, c.proxy.R) * Tt;
  const Eigen::FullPivLU<Mat6> lu(c.sys.A);
  const Eigen::Matrix<double, 6, 2> AinvH = lu.solve(H);
  const Eigen::Matrix<double, 6, 2> Hs = s.d.asDiagonal() * H;
  const Eigen::Matrix2d Ws = Hs.transpose() * As.fullPivLu().solve(Hs);
  s.bound *= kappa(Ws);
  const Vec6 V0 = lu.solve(c.sys.b);
  const Eigen::Vector2d lambda = (H.transpose() * AinvH).fullPivLu().solve(-H.transpose() * V0);
  // lambda's error scales with |W^-1| |H| |V0| (the right-hand side H^T V0 cancels when the
  // frictionless slip is small), in the scaled unknowns |Ws^-1| |Hs| |y0|.
  s.lambda_scale = lambda.norm() + Ws.inverse().norm() * Hs.norm() * V0.cwiseQuotient(s.d).norm();
  s.r_norm = bc.r.norm();
  const Mat6 Gd = c.normal.G * s.d.asDiagonal();
  const double y = std::max(ref.V.cwiseQuotient(s.d).cwiseAbs().maxCoeff(),
                            V0.cwiseQuotient(s.d).cwiseAbs().maxCoeff());
  s.fn_scale = std::abs(bc.n.dot(c.normal.f0.head<3>())) +
               Gd.topRows<3>().cwiseAbs().rowwise().sum().maxCoeff() * y;
  if (ref.sliding && lambda.norm() > 0.0) {
    const Vec6 Vd = AinvH * (lambda / lambda.norm());
    const double beta = bc.n.dot((c.normal.G * Vd).head<3>());
    const double slope = 1.0 - c.fp.mu * beta;
    const double amplification =
        (1.0 + c.fp.mu * (s.fn_scale / s.lambda_scale + std::abs(beta))) / slope;
    // Not finite when the normal wrench is not (the adversarial cases): alpha is then not > 0
    // or f_n is infinite, and both twins take s = 0 or stick without the scalar's error.
    if (std::isfinite(amplification) && amplification > 0.0) s.bound *= amplification;
  }
  return s;
}

double rel(double diff, double scale) {
  if (diff == 0.0) return 0.0;
  return scale > 0.0 ? diff / scale : INFINITY;
}

// |other - ref| over the scales of the header, divided by the bound (<= 1 passes).
double ratio(const FrictionState& c, const FrictionSolution& ref, const FrictionSolution& other) {
  const Scales s = scales(c, ref);
  const Vec6 y = ref.V.cwiseQuotient(s.d);
  const Vec6 y0 = c.sys.A.fullPivLu().solve(c.sys.b).cwiseQuotient(s.d);
  double e = rel((other.V - ref.V).cwiseQuotient(s.d).cwiseAbs().maxCoeff(),
                 std::max(y.cwiseAbs().maxCoeff(), y0.cwiseAbs().maxCoeff()));
  if (s.active) {
    e = std::max({e, rel((other.f_t - ref.f_t).cwiseAbs().maxCoeff(), s.lambda_scale),
                  rel((other.F - ref.F).cwiseAbs().maxCoeff(), s.lambda_scale * (1.0 + s.r_norm)),
                  rel(std::abs(other.f_n - ref.f_n), s.fn_scale)});
  }
  return e / s.bound;
}

// The registry's friction solves but the reference's.
std::vector<const Implementation*> twins() {
  std::vector<const Implementation*> out;
  for (const Implementation* i : implementations()) {
    if (i->friction != implementations()[0]->friction) out.push_back(i);
  }
  return out;
}

struct Tally {
  long cases = 0, stick = 0, slide = 0, inactive = 0, regime_differs = 0;
  double worst = 0.0;
};

// One case through the reference and `twin`: the same verdict, the same regime (unless `boundary`,
// where either is allowed), the same activity, and every output within the bound.
void compare(const FrictionState& c, FrictionSolve twin, bool boundary, Tally* t) {
  FrictionSolution ref, other;
  const bool ok_ref =
      solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &ref);
  const bool ok = twin(c.sys, c.contacts, c.proxy, c.normal, c.fp, &other);
  ASSERT_EQ(ok_ref, ok);
  ASSERT_TRUE(ok);
  ++t->cases;
  EXPECT_EQ(ref.active, other.active);
  if (!ref.active) {
    ++t->inactive;
  } else {
    (ref.sliding ? t->slide : t->stick) += 1;
  }
  if (ref.sliding != other.sliding) {
    ++t->regime_differs;
    EXPECT_TRUE(boundary) << "the twins disagree on the regime away from the boundary";
  }
  const double r = ratio(c, ref, other);
  t->worst = std::max(t->worst, r);
  EXPECT_LE(r, 1.0) << "sliding " << ref.sliding << " mu " << c.fp.mu;
}

void print(const char* what, const Tally& t) {
  std::printf(
      "%s: %ld cases (stick %ld, slide %ld, inactive %ld), regime differs %ld; worst "
      "|twin - reference| / bound %.3e\n",
      what, t.cases, t.stick, t.slide, t.inactive, t.regime_differs, t.worst);
}

TEST(FrictionTwin, TheRegistryHasATwin) {
  ASSERT_NE(implementations()[0]->friction, nullptr);
  EXPECT_EQ(implementations()[0]->friction, &solve_with_friction_unchecked);
  ASSERT_EQ(twins().size(), implementations().size() - 1);
  EXPECT_EQ(find_implementation("fast")->friction, &fast::solve_with_friction_unchecked);
}

TEST(FrictionTwin, RandomCasesAgreeWithinTheBound) {
  const unsigned seed = 49;
  const long n = testing::stress_count(20000, 400000);
  for (const Implementation* impl : twins()) {
    Rng rng(seed);
    Tally t;
    for (long i = 0; i < n; ++i)
      compare(testing::random_friction_case(rng), impl->friction, false, &t);
    std::printf("seed %u, %s ", seed, impl->name());
    print("random", t);
    EXPECT_GT(t.stick, n / 20);
    EXPECT_GT(t.slide, n / 20);
    EXPECT_GT(t.inactive, n / 50);
    EXPECT_EQ(t.regime_differs, 0);
  }
}

// The built-in scenes' contact ticks (the fast pipeline's closed loop): the states the servo
// tick solves.
TEST(FrictionTwin, TheScenesContactTicksAgreeWithinTheBound) {
  for (const char* scene : {"drill", "probe", "probe-groove"}) {
    const std::vector<FrictionState> states = record_friction_states(scene, 5000);
    ASSERT_GT(states.size(), 500u) << scene;
    for (const Implementation* impl : twins()) {
      Tally t;
      for (const FrictionState& c : states) compare(c, impl->friction, false, &t);
      std::printf("%s %s ", scene, impl->name());
      print("contact ticks", t);
      EXPECT_GT(t.stick + t.slide, 100);
    }
  }
}

// Exactly at the boundary: mu set so that |f_stick| = mu f_n(V_stick) for the reference's
// sticking solution, and one ulp either side. The sliding solution equals the sticking one there,
// so whichever regime each twin picks, the results agree within the bound.
TEST(FrictionTwin, TheStickSlideBoundaryAgreesEitherWay) {
  const unsigned seed = 50;
  Rng rng(seed);
  for (const Implementation* impl : twins()) {
    Tally t;
    long boundary_cases = 0;
    while (boundary_cases < 3000) {
      FrictionState c = testing::random_friction_case(rng);
      FrictionSolution ref;
      ASSERT_TRUE(solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &ref));
      if (!ref.active || ref.sliding || !(ref.f_n > 0.0) || !(ref.f_t.norm() > 0.0)) continue;
      ++boundary_cases;
      const double mu = ref.f_t.norm() / ref.f_n;
      for (double m : {mu, std::nextafter(mu, 0.0), std::nextafter(mu, INFINITY)}) {
        c.fp.mu = m;
        compare(c, impl->friction, true, &t);
      }
    }
    std::printf("seed %u, %s ", seed, impl->name());
    print("boundary", t);
    EXPECT_GT(t.slide, 0);  // both regimes are reached at the boundary
    EXPECT_GT(t.stick, 0);
  }
}

// Without friction (disabled, mu = 0, no member penetrating, no contact): the frictionless solve,
// bitwise fast::pmi_try_solve's (the same factor and solve: the fast pipeline's friction skip is
// exact), and within the bound of the reference's.
TEST(FrictionTwin, WithoutFrictionItIsThePmiSolve) {
  Rng rng(51);
  long n = 0;
  for (int i = 0; i < 2000; ++i) {
    FrictionState c = testing::random_friction_case(rng);
    switch (i % 4) {
      case 0:
        c.fp.enabled = false;
        break;
      case 1:
        c.fp.mu = 0.0;
        break;
      case 2:
        c.contacts.clear();
        break;
      default:
        for (Contact& m : c.contacts) m.x_o = c.proxy.x + c.proxy.R * m.r - 1e-4 * m.n;
    }
    FrictionSolution ref, fast;
    ASSERT_TRUE(solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &ref));
    ASSERT_TRUE(
        fast::solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &fast));
    EXPECT_FALSE(fast.active);
    EXPECT_FALSE(fast.sliding);
    EXPECT_EQ(fast.f_t, Vec3::Zero());
    EXPECT_EQ(fast.F, Vec6::Zero());
    EXPECT_EQ(fast.f_n, 0.0);
    Vec6 V;
    ASSERT_TRUE(fast::pmi_try_solve(c.sys, &V));
    EXPECT_EQ(testing::unequal_entries(fast.V, V), 0);
    EXPECT_LE(ratio(c, ref, fast), 1.0);
    ++n;
  }
  EXPECT_EQ(n, 2000);
}

// Zero, NaN and infinite entries, singular A: failure exactly where the reference fails, and
// where neither does, the same verdict on the outputs' finiteness and agreement within the bound.
TEST(FrictionTwin, AdversarialInputsFailWhereTheReferenceFails) {
  Rng rng(52);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  long failures = 0, nonfinite = 0, agreed = 0;
  auto check = [&](const FrictionState& c) {
    FrictionSolution ref, fast;
    const bool ok_ref =
        solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &ref);
    const bool ok =
        fast::solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &fast);
    EXPECT_EQ(ok_ref, ok);
    if (!ok_ref || !ok) {
      ++failures;
      return;
    }
    EXPECT_EQ(ref.active, fast.active);
    const bool finite_ref = ref.V.allFinite() && ref.F.allFinite() && ref.f_t.allFinite();
    const bool finite = fast.V.allFinite() && fast.F.allFinite() && fast.f_t.allFinite();
    EXPECT_EQ(finite_ref, finite);
    if (!finite_ref || !finite) {
      ++nonfinite;
      return;
    }
    EXPECT_EQ(std::isfinite(ref.f_n), std::isfinite(fast.f_n));
    if (std::isfinite(ref.f_n)) {
      EXPECT_LE(ratio(c, ref, fast), 1.0);
    } else {
      EXPECT_EQ(ref.f_n, fast.f_n);
    }
    ++agreed;
  };
  auto active_case = [&] {
    for (;;) {
      FrictionState c = testing::random_friction_case(rng);
      if (blended_contact(c.contacts, c.proxy).active) return c;
    }
  };
  for (double bad : {nan, inf, -inf}) {
    for (int k = 0; k < 36; ++k) {  // every entry of A
      FrictionState c = active_case();
      c.sys.A(k) = bad;
      check(c);
    }
    for (int k = 0; k < 6; ++k) {  // b, the normal wrench's f0 and force rows of G
      FrictionState c = active_case();
      c.sys.b(k) = bad;
      check(c);
      c = active_case();
      c.normal.f0(k) = bad;
      check(c);
      c = active_case();
      c.normal.G(k % 3, k) = bad;
      check(c);
    }
    FrictionState c = active_case();  // a member's weight: the blended contact is not finite
    c.contacts[0].weight = bad;
    check(c);
    c = active_case();  // a member's position: it does not penetrate
    c.contacts[0].x_o.x() = bad;
    check(c);
  }
  // Zero: b = 0 gives V = 0 and no friction force, exactly; A = 0 and exactly singular A fail.
  {
    FrictionState c = active_case();
    c.sys.b.setZero();
    FrictionSolution fast;
    ASSERT_TRUE(
        fast::solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &fast));
    EXPECT_EQ(fast.V, Vec6::Zero());
    EXPECT_EQ(fast.f_t, Vec3::Zero());
    check(c);
  }
  for (int k = 0; k < 4; ++k) {
    FrictionState c = active_case();
    if (k == 0) c.sys.A.setZero();
    if (k == 1) {
      c.sys.A.row(2).setZero();
      c.sys.A.col(2).setZero();
    }
    if (k == 2) c.sys.A.row(4) = c.sys.A.row(1);
    if (k == 3) c.sys.A.col(5) = 2.0 * c.sys.A.col(0);
    FrictionSolution fast;
    EXPECT_FALSE(
        fast::solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &fast));
    check(c);
  }
  std::printf("adversarial: %ld fail in both, %ld non-finite in both, %ld agree within the bound\n",
              failures, nonfinite, agreed);
  EXPECT_GE(failures, 3 * 36 + 2 * 6 + 4);  // A and b not finite, singular A
  EXPECT_GT(nonfinite, 0);
  EXPECT_GT(agreed, 3 * 6);
}

// The bound can fail: a relative error of 1e-9 planted in any output, or the sticking force's
// sign flipped, is far above it (the comparison is the one the tests above use).
TEST(FrictionTwin, PlantedErrorsFail) {
  Rng rng(53);
  long planted = 0;
  for (int i = 0; i < 200; ++i) {
    const FrictionState c = testing::random_friction_case(rng);
    FrictionSolution ref, fast;
    ASSERT_TRUE(solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &ref));
    ASSERT_TRUE(
        fast::solve_with_friction_unchecked(c.sys, c.contacts, c.proxy, c.normal, c.fp, &fast));
    ASSERT_LE(ratio(c, ref, fast), 1.0);
    FrictionSolution m = fast;
    const Vec6 d = pmi_scaling(c.sys.A);  // the error planted in the scaled unknowns
    m.V(i % 6) += 1e-9 * d(i % 6) * m.V.cwiseQuotient(d).cwiseAbs().maxCoeff();
    EXPECT_GT(ratio(c, ref, m), 1.0);
    if (!ref.active || ref.f_t.norm() == 0.0) continue;
    m = fast;
    m.f_t *= 1.0 + 1e-9;
    EXPECT_GT(ratio(c, ref, m), 1.0);
    m = fast;
    m.F = -m.F;
    EXPECT_GT(ratio(c, ref, m), 1.0);
    if (ref.f_n > 0.0) {
      m = fast;
      m.f_n *= 1.0 + 1e-9;
      EXPECT_GT(ratio(c, ref, m), 1.0);
    }
    ++planted;
  }
  EXPECT_GT(planted, 50);
}

}  // namespace
}  // namespace dentsim
