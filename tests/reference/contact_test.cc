// Tests for reference/contact.h: penalty contact (2.15)-(2.19) with PMI terms (4.9), damping,
// the torque-frame reading, and the aggregation of a contact set.
//
// The PMI proxy step is assembled locally with Eigen ((M 2/T - G) V_hat = M 2/T V_k + f0, then
// V_k+1 = 2 V_hat - V_k, x_k+1 = x_k + T v_hat, R_k+1 = R_k exp(S(w_hat T)), (2.7)-(2.8), (4.9))
// so this file does not depend on the lead's reference/pmi.h. Seeds are fixed and printed.
#include "reference/contact.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "reference/pmi.h"
#include "tests/support/contacts.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;

double uni(Rng& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

Vec3 random_vec(Rng& rng, double scale) {
  return Vec3(uni(rng, -1, 1), uni(rng, -1, 1), uni(rng, -1, 1)) * scale;
}

Vec3 random_unit(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

Mat3 random_rotation(Rng& rng) { return exp_so3(random_unit(rng) * uni(rng, 0.0, 3.0)); }

Pose random_pose(Rng& rng) { return Pose{random_vec(rng, 0.05), random_rotation(rng)}; }

Vec6 random_twist(Rng& rng) { return stack(random_vec(rng, 0.2), random_vec(rng, 3.0)); }

// The pose after moving with constant twist V for time h: x + h v, R exp(S(w h)).
Pose advance(const Pose& p, const Vec6& V, double h) {
  return Pose{p.x + h * lin(V), p.R * exp_so3(h * ang(V))};
}

using testing::make_contact;

double rel_err(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max({a.norm(), b.norm(), 1e-300});
}

TEST(Contact, DepthAndJacobianMatchFiniteDifferences) {
  const unsigned seed = 11;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  double worst_J = 0.0, worst_rate = 0.0;
  for (int s = 0; s < 500; ++s) {
    const Pose p = random_pose(rng);
    const Vec3 n = random_unit(rng);
    const Vec3 r = random_vec(rng, 0.03);
    const Contact c = make_contact(p, n, r, uni(rng, -1e-3, 1e-3), 1e4);
    const Vec6 V = random_twist(rng);
    // Depth is n^T (x_o - x2 - R2 r).
    EXPECT_NEAR(penetration_depth(c, p), n.dot(c.x_o - p.x - p.R * r), 1e-16);
    EXPECT_NEAR(penetration_depth(c, p), c.depth, 1e-15);
    // xdot_c = J_c V against a central difference of x_c along V.
    const double h = 1e-6;
    const Vec3 xc_p = contact_point(c, advance(p, V, h));
    const Vec3 xc_m = contact_point(c, advance(p, V, -h));
    const Vec3 fd = (xc_p - xc_m) / (2 * h);
    const Mat36 J = contact_point_jacobian(r, p.R);
    worst_J = std::max(worst_J, (J * V - fd).norm() / fd.norm());
    // d(delta)/dt = n^T [-I, R S(r)] V, the form printed in (2.16).
    Mat36 printed;
    printed << -Mat3::Identity(), p.R * skew(r);
    const double rate = (n.transpose() * printed * V)(0);
    EXPECT_NEAR(rate, -(n.transpose() * J * V)(0), 1e-15);
    const double fd_rate =
        (penetration_depth(c, advance(p, V, h)) - penetration_depth(c, advance(p, V, -h))) /
        (2 * h);
    worst_rate = std::max(worst_rate, std::abs(rate - fd_rate) / (1e-3 + std::abs(fd_rate)));
    // The wrench map is J_c^T.
    EXPECT_EQ((contact_wrench_map(r, p.R) - J.transpose()).norm(), 0.0);
  }
  std::printf("worst relative J_c error %.3e, worst depth-rate error %.3e\n", worst_J, worst_rate);
  EXPECT_LT(worst_J, 1e-8);
  EXPECT_LT(worst_rate, 1e-8);
}

// V^T F = -dU/dt for the spring part: pins the body-frame torque S(r) R^T f (and shows that the
// printed R^T S(r) f is wrong once R != I).
TEST(Contact, WrenchPowerEqualsMinusPotentialRate) {
  const unsigned seed = 12;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  double worst = 0.0, best_printed = 1e300;
  std::vector<double> printed_errs;
  for (int s = 0; s < 500; ++s) {
    const Pose p = random_pose(rng);
    std::vector<Contact> set;
    const int m = 1 + static_cast<int>(rng() % 5);
    for (int i = 0; i < m; ++i) {
      set.push_back(make_contact(p, random_unit(rng), random_vec(rng, 0.03), uni(rng, 5e-5, 1e-3),
                                 uni(rng, 1e2, 1e5), 0.0, uni(rng, 0.1, 2.0)));
    }
    const Vec6 V = random_twist(rng);
    const AffineWrench F = contact_wrench(set, p, 1e-3, Scheme::kExplicit);
    EXPECT_EQ(F.G.norm(), 0.0);  // no damping: the explicit spring is constant in V
    const double power = V.dot(F.at(V));
    // Fourth-order central difference of U along the motion with twist V.
    const double h = 1e-5;
    const auto U = [&](double t) { return contact_potential(set, advance(p, V, t)); };
    const double dU = (8.0 * (U(h) - U(-h)) - (U(2 * h) - U(-2 * h))) / (12.0 * h);
    worst = std::max(worst, std::abs(power + dU) / (std::abs(dU) + 1e-6));
    // The printed torque [I; R^T S(r)] f for comparison.
    const std::vector<double> w = contact_weights(set);
    Vec6 printed = Vec6::Zero();
    for (std::size_t i = 0; i < set.size(); ++i) {
      const Vec3 f = w[i] * set[i].stiffness * penetration_depth(set[i], p) * set[i].n;
      printed += stack(f, p.R.transpose() * skew(set[i].r) * f);
    }
    const double printed_err = std::abs(V.dot(printed) + dU) / (std::abs(dU) + 1e-6);
    best_printed = std::min(best_printed, printed_err);
    printed_errs.push_back(printed_err);
  }
  std::nth_element(printed_errs.begin(), printed_errs.begin() + 250, printed_errs.end());
  std::printf(
      "worst relative power error %.3e; printed R^T S(r) reading: smallest error %.3e, "
      "median %.3e\n",
      worst, best_printed, printed_errs[250]);
  EXPECT_LT(worst, 1e-7);
  // The printed reading fails the identity on every sample, by far more than the FD error.
  EXPECT_GT(best_printed, 1e3 * worst);
}

// The PMI wrench equals its definition, written independently with cross products.
TEST(Contact, MidpointWrenchMatchesDefinitionAndIsDissipativeInV) {
  const unsigned seed = 13;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  for (int s = 0; s < 300; ++s) {
    const Pose p = random_pose(rng);
    const double T = uni(rng, 1e-4, 2e-3);
    std::vector<Contact> set;
    const int m = 1 + static_cast<int>(rng() % 4);
    for (int i = 0; i < m; ++i) {
      set.push_back(make_contact(p, random_unit(rng), random_vec(rng, 0.03), uni(rng, -5e-4, 1e-3),
                                 uni(rng, 1e2, 1e5), uni(rng, 0.0, 20.0), uni(rng, 0.0, 2.0)));
    }
    const Vec6 V = random_twist(rng);
    const AffineWrench F = contact_wrench(set, p, T, Scheme::kMidpoint);
    double wsum = 0.0;
    for (const Contact& c : set) wsum += c.weight;
    Vec6 expect = Vec6::Zero();
    for (const Contact& c : set) {
      const double delta = c.n.dot(c.x_o - p.x - p.R * c.r);
      if (delta <= 0.0) continue;
      const Vec3 xdot_c = lin(V) + p.R * ang(V).cross(c.r);
      const double rate = -c.n.dot(xdot_c);
      const double w = c.weight / wsum;
      const Vec3 f = w * (c.stiffness * (delta + 0.5 * T * rate) + c.damping * rate) * c.n;
      expect += stack(f, p.R.transpose() * (p.R * c.r).cross(f));
    }
    EXPECT_LT(rel_err(F.at(V), expect), 1e-12) << "sample " << s;
    // G symmetric negative semidefinite: the velocity-dependent part never produces power.
    EXPECT_LT((F.G - F.G.transpose()).norm(), 1e-12 * (1.0 + F.G.norm()));
    const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (F.G + F.G.transpose()));
    EXPECT_LE(eig.eigenvalues().maxCoeff(), 1e-12 * (1.0 + F.G.norm()));
    // The explicit scheme keeps the spring value and only the damper depends on V.
    const AffineWrench E = contact_wrench(set, p, T, Scheme::kExplicit);
    EXPECT_LT(rel_err(E.f0, F.f0), 1e-15);
  }
}

// --- local PMI proxy -------------------------------------------------------------------------

struct Body {
  Mat6 M;
  Pose pose;
  Vec6 V = Vec6::Zero();
};

// One PMI tick with the contact set and a constant external force f_ext (world); returns V_hat.
Vec6 pmi_tick(Body& b, const std::vector<Contact>& set, const Vec3& f_ext, double T) {
  const AffineWrench F = contact_wrench(set, b.pose, T, Scheme::kMidpoint);
  const Mat6 A = b.M * (2.0 / T) - F.G;  // (4.9)
  const Vec6 rhs = b.M * (2.0 / T) * b.V + F.f0 + stack(f_ext, Vec3::Zero());
  const Vec6 V_hat = A.fullPivLu().solve(rhs);
  b.V = 2.0 * V_hat - b.V;  // (2.7)
  b.pose.x += T * lin(V_hat);
  b.pose.R = b.pose.R * exp_so3(T * ang(V_hat));  // (2.18)
  return V_hat;
}

double energy(const Body& b, const std::vector<Contact>& set, const Vec3& f_ext) {
  return 0.5 * b.V.dot(b.M * b.V) + contact_potential(set, b.pose) - f_ext.dot(b.pose.x);
}

bool in_contact(const std::vector<Contact>& set, const Pose& p) {
  for (const Contact& c : set) {
    if (penetration_depth(c, p) > 0.0) return true;
  }
  return false;
}

Mat6 proxy_inertia() {
  return block_diag(0.05 * Mat3::Identity(), Vec3(2e-5, 3e-5, 4e-5).asDiagonal());
}

// Zero damping, pure translation (r = 0, so no torque arises; R != I): KE + contact potential +
// gravity potential is conserved to round-off on every tick that starts and ends in contact, at
// any stiffness and tick length. Two starts: 0.2 mm above the plane (bounces; the ticks that enter
// or leave are excluded) and inside at 1.5x the equilibrium depth (never leaves).
// Round-off policy: the PMI identity holds to the backward error of the 6x6 solve, i.e.
// eps * cond(A) with cond(A) = 1 + K T^2 / (4 m) here, relative to the magnitudes of the terms
// summed into E (|g||x| for -g^T x); the test allows 1e-13 * cond(A) (~450 eps * cond(A)).
// (A fixed body point below the centre, r = -rho n, would be an inverted pendulum: round-off
// tilts grow exponentially, so the translation case uses r = 0; rotation is the next test.)
TEST(Contact, PmiBounceConservesEnergyForTranslation) {
  const unsigned seed = 14;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  double worst = 0.0, worst_abs = 0.0;
  long contact_ticks = 0;
  for (double K : {1e3, 1e5, 1e7, 1e9}) {
    for (double T : {1e-4, 1e-3, 4e-3}) {
      for (bool start_inside : {false, true}) {
        const Vec3 n = random_unit(rng);
        Body b{proxy_inertia(), Pose{Vec3::Zero(), random_rotation(rng)}};
        const double m = b.M(0, 0);
        const Vec3 g = -9.81 * m * n;  // weight pressing it onto the plane: repeated bounces
        const double depth0 = start_inside ? 1.5 * 9.81 * m / K : -2e-4;
        std::vector<Contact> set{make_contact(b.pose, n, Vec3::Zero(), depth0, K)};
        const Vec3 t = n.cross(random_unit(rng)).normalized();
        b.V = stack((start_inside ? 0.0 : -0.1) * n + 0.05 * t, Vec3::Zero());
        long ticks = 0;
        for (int k = 0; k < 3000; ++k) {
          const bool before = in_contact(set, b.pose);
          const double E0 = energy(b, set, g);
          // Round-off scale: the magnitudes of the terms summed into E (|g||x| for -g^T x).
          const double scale = 0.5 * b.V.dot(b.M * b.V) + contact_potential(set, b.pose) +
                               g.norm() * b.pose.x.norm() + 1e-12;
          pmi_tick(b, set, g, T);
          EXPECT_EQ(ang(b.V).norm(), 0.0);
          if (before && in_contact(set, b.pose)) {
            const double cond = 1.0 + K * T * T / (4.0 * m);
            const double err = std::abs(energy(b, set, g) - E0) / scale;
            worst = std::max(worst, err / cond);
            worst_abs = std::max(worst_abs, err);
            ++ticks;
          }
        }
        if (start_inside) {
          EXPECT_EQ(ticks, 3000) << "K " << K << " T " << T;
        }
        contact_ticks += ticks;
      }
    }
  }
  std::printf(
      "%ld in-contact ticks, worst relative energy change per tick %.3e, "
      "worst relative change / cond(A) %.3e\n",
      contact_ticks, worst_abs, worst);
  EXPECT_LT(worst, 1e-13);
}

// With rotation (r != 0, w != 0) the linearised rotation (2.18) makes the energy error per tick
// O(T^2): exactly dE = K/2 e (delta_k+1 + delta_k + T d(delta)) with
// e = -n^T R_k (exp(S(w_hat T)) - I - S(w_hat T)) r, |e| <= (|w_hat| T)^2 |r| / 2.
// The test checks that bound on every in-contact tick and that halving T quarters the error.
TEST(Contact, PmiEnergyErrorWithRotationIsSecondOrder) {
  const unsigned seed = 15;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  const Vec3 n = random_unit(rng);
  const Mat3 R0 = random_rotation(rng);
  const Vec3 r = R0.transpose() * (-0.01 * n + 0.015 * n.cross(random_unit(rng)).normalized());
  const double K = 2e4;
  const double duration = 0.05;
  std::vector<double> worst_per_T;
  for (double T : {1e-3, 5e-4, 2.5e-4}) {
    Body b{proxy_inertia(), Pose{Vec3::Zero(), R0}};
    std::vector<Contact> set{make_contact(b.pose, n, r, -1e-4, K)};
    b.V = stack(-0.05 * n, Vec3(3.0, -2.0, 1.0));
    const Vec3 g = -9.81 * 0.05 * n;
    double worst = 0.0;
    long ticks = 0;
    const long steps = std::lround(duration / T);
    for (long k = 0; k < steps; ++k) {
      const double d0 = penetration_depth(set[0], b.pose);
      const double E0 = energy(b, set, g);
      const Mat3 R_k = b.pose.R;
      const Vec6 V_hat = pmi_tick(b, set, g, T);
      const double d1 = penetration_depth(set[0], b.pose);
      if (d0 > 0.0 && d1 > 0.0) {
        const double dE = std::abs(energy(b, set, g) - E0);
        const double th = ang(V_hat).norm() * T;
        const double Tdd = -T * (n.transpose() * contact_point_jacobian(r, R_k) * V_hat)(0);
        const double bound = 0.5 * K * 0.5 * th * th * r.norm() * std::abs(d0 + d1 + Tdd);
        EXPECT_LE(dE, bound * (1 + 1e-9) + 1e-15) << "T " << T << " tick " << k;
        worst = std::max(worst, dE);
        ++ticks;
      }
    }
    std::printf("T %.2e: %ld in-contact ticks, worst |dE| per tick %.3e J (/T^2 = %.3e)\n", T,
                ticks, worst, worst / (T * T));
    EXPECT_GT(ticks, 10);
    EXPECT_GT(worst, 0.0);
    worst_per_T.push_back(worst);
  }
  for (std::size_t i = 1; i < worst_per_T.size(); ++i) {
    const double ratio = worst_per_T[i - 1] / worst_per_T[i];
    std::printf("error ratio for T -> T/2: %.3f (O(T^2) -> 4)\n", ratio);
    EXPECT_GT(ratio, 3.0);
    EXPECT_LT(ratio, 5.5);
  }
}

// With contact damping (translation) every in-contact tick loses exactly T w B (d delta)^2 >= 0.
TEST(Contact, DampedPmiContactEnergyDecreasesMonotonically) {
  const unsigned seed = 16;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  const double T = 1e-3, K = 5e4, B = 8.0;
  const Vec3 n = random_unit(rng);
  Body b{proxy_inertia(), Pose{Vec3::Zero(), random_rotation(rng)}};
  const Vec3 r = b.pose.R.transpose() * (-1e-3 * n);
  std::vector<Contact> set{make_contact(b.pose, n, r, -1e-4, K, B)};
  b.V = stack(-0.2 * n, Vec3::Zero());
  const Vec3 g = -9.81 * 0.05 * n;
  long ticks = 0;
  double worst = 0.0, lost = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const bool before = in_contact(set, b.pose);
    const double E0 = energy(b, set, g);
    const Vec6 V_hat = pmi_tick(b, set, g, T);
    if (before && in_contact(set, b.pose)) {
      const double E1 = energy(b, set, g);
      const double rate = -n.dot(lin(V_hat));
      const double expected = -T * B * rate * rate;
      EXPECT_LE(E1 - E0, 1e-15);
      worst = std::max(worst, std::abs((E1 - E0) - expected) / (std::abs(E0) + 1e-12));
      lost += E0 - E1;
      ++ticks;
    }
  }
  std::printf(
      "%ld in-contact ticks, dissipated %.6e J, worst relative deviation from "
      "T B (d delta)^2 %.3e\n",
      ticks, lost, worst);
  EXPECT_GT(ticks, 500);
  EXPECT_GT(lost, 0.0);
  EXPECT_LT(worst, 1e-12);
}

// The same geometric contact reported 1, 4, 16, 64 times, or by the faces of a 2x, 4x, 8x finer
// voxel grid at the same depth, gives the same wrench (f0 and G).
TEST(Contact, AggregationMakesForceIndependentOfReportCount) {
  const unsigned seed = 17;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  double worst = 0.0;
  for (int s = 0; s < 50; ++s) {
    const Pose p = random_pose(rng);
    const Vec3 n = random_unit(rng);
    const double rho = 1e-3, depth = uni(rng, 1e-6, 2e-4), K = uni(rng, 1e3, 1e5);
    const double B = uni(rng, 0.0, 10.0), T = 1e-3;
    const Vec3 r = p.R.transpose() * (-rho * n);  // tip sphere point facing the surface
    const Contact one = make_contact(p, n, r, depth, K, B);
    const AffineWrench ref = contact_wrench(std::span(&one, 1), p, T, Scheme::kMidpoint);
    ASSERT_GT(ref.f0.norm(), 0.0);
    for (int N : {4, 16, 64}) {
      std::vector<Contact> set(N, one);
      for (Contact& c : set) c.weight = 0.7;
      const AffineWrench F = contact_wrench(set, p, T, Scheme::kMidpoint);
      worst = std::max({worst, rel_err(F.f0, ref.f0), rel_err(F.G, ref.G)});
    }
    // Finer grids: the coarse face of size h split into m x m faces, each at its own centre on the
    // same plane, weighted by area (what a collision stage would report).
    Vec3 t1 = n.cross(random_unit(rng)).normalized(), t2 = n.cross(t1);
    const double h = 2e-3;
    for (int m : {2, 4, 8}) {
      std::vector<Contact> set;
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) {
          Contact c = one;
          c.x_o += ((i + 0.5) / m - 0.5) * h * t1 + ((j + 0.5) / m - 0.5) * h * t2;
          c.weight = (h / m) * (h / m);
          set.push_back(c);
        }
      }
      const AffineWrench F = contact_wrench(set, p, T, Scheme::kMidpoint);
      worst = std::max({worst, rel_err(F.f0, ref.f0), rel_err(F.G, ref.G)});
    }
  }
  std::printf("worst relative wrench difference across report counts %.3e\n", worst);
  EXPECT_LT(worst, 1e-12);
}

// A set's stiffness never exceeds the stiffest member's K, however many members report.
TEST(Contact, SetStiffnessIsAtMostTheStiffestMember) {
  const unsigned seed = 18;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  for (int s = 0; s < 200; ++s) {
    const Pose p = random_pose(rng);
    const double T = 1e-3;
    std::vector<Contact> set;
    double kmax = 0.0;
    const int m = 1 + static_cast<int>(rng() % 64);
    for (int i = 0; i < m; ++i) {
      const double K = uni(rng, 1e2, 1e5);
      kmax = std::max(kmax, K);
      set.push_back(make_contact(p, random_unit(rng), Vec3::Zero(), uni(rng, 1e-6, 1e-4), K, 0.0,
                                 uni(rng, 0.0, 1.0)));
    }
    // With r = 0 the translational block of G is -T/2 sum w_i K_i n_i n_i^T.
    const AffineWrench F = contact_wrench(set, p, T, Scheme::kMidpoint);
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(-F.G.topLeftCorner<3, 3>() / (0.5 * T));
    EXPECT_LE(eig.eigenvalues().maxCoeff(), kmax * (1 + 1e-12));
    EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-9);
  }
}

// Unilateral: a member with delta <= 0 contributes nothing; the spring never pulls at t_k.
TEST(Contact, NonPenetratingMembersGiveNoForce) {
  const unsigned seed = 19;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  long active = 0, inactive = 0;
  for (int s = 0; s < 500; ++s) {
    const Pose p = random_pose(rng);
    const Vec3 n = random_unit(rng);
    const Vec3 r = random_vec(rng, 0.02);
    const double depth = uni(rng, -1e-3, 1e-3);
    const Contact c = make_contact(p, n, r, s % 10 == 0 ? 0.0 : depth, 1e4, 5.0);
    const AffineWrench F = contact_wrench(std::span(&c, 1), p, 1e-3, Scheme::kMidpoint);
    if (penetration_depth(c, p) <= 0.0) {
      EXPECT_EQ(F.f0.norm(), 0.0);
      EXPECT_EQ(F.G.norm(), 0.0);
      EXPECT_EQ(contact_potential(std::span(&c, 1), p), 0.0);
      ++inactive;
    } else {
      EXPECT_GT(n.dot(lin(F.f0)), 0.0);  // pushes out of the tooth
      ++active;
    }
    // Adding a non-penetrating member to an active set changes only the weights, not the form.
    Contact far = make_contact(p, n, r, -std::abs(depth) - 1e-6, 1e4, 5.0);
    Contact deep = make_contact(p, n, r, std::abs(depth) + 1e-6, 1e4, 5.0);
    const std::vector<Contact> pair{deep, far};
    const AffineWrench Fp = contact_wrench(pair, p, 1e-3, Scheme::kMidpoint);
    const AffineWrench Fd = contact_wrench(std::span(&deep, 1), p, 1e-3, Scheme::kMidpoint);
    EXPECT_LT(rel_err(Fp.f0, 0.5 * Fd.f0), 1e-14);
    EXPECT_LT(rel_err(Fp.G, 0.5 * Fd.G), 1e-14);
  }
  std::printf("%ld active, %ld inactive samples\n", active, inactive);
  EXPECT_GT(active, 100);
  EXPECT_GT(inactive, 100);
}

TEST(Contact, WeightsAreNormalised) {
  std::vector<Contact> set(4);
  set[0].weight = 1.0;
  set[1].weight = 3.0;
  set[2].weight = 0.0;
  set[3].weight = 4.0;
  const std::vector<double> w = contact_weights(set);
  ASSERT_EQ(w.size(), 4u);
  EXPECT_DOUBLE_EQ(w[0], 0.125);
  EXPECT_DOUBLE_EQ(w[1], 0.375);
  EXPECT_EQ(w[2], 0.0);
  EXPECT_DOUBLE_EQ(w[3], 0.5);
  for (Contact& c : set) c.weight = 0.0;
  for (double wi : contact_weights(set)) EXPECT_EQ(wi, 0.25);
  EXPECT_TRUE(contact_weights({}).empty());
}

template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

// The surface-proxy contact (reference/tooth/sdf.h) is the spring K (g - c) to an anchor g; where
// the anchor is held (h = 1) it is as stiff across its normal as along it, and contact_wrench
// integrates only the part along n. reference/contact.h derives that the part left explicit is
// stable iff K_e T/2 <= b (the implicit damping across n), whatever the mass. A proxy pushed 1 mm
// into a held anchor by a constant force K delta_0 (the hand through the coupling), 0.1 mm off
// to the side, the contact recomputed from g and c every tick, the proxy's own damping b the only
// damper, at the stress run's K and T (docs/results/reliability.md: 26694 N/m, 2 ms), for
// masses 100 times apart; E = 1/2 m v^2 + 1/2 K |g - c|^2 + K delta_0 z above its minimum:
// - b = 0.9 K T/2 with the spring across n explicit: E grows (here 30-50 fold within 2000 ticks,
//   until the side swing is as large as the push's depth and the geometry turns it; with a device
//   pulling the proxy back, the cause of that run's explosion);
// - with add_anchored_spring_unchecked (K_imp = K - 2b/T implicit): it never grows;
// - b = 1.1 K T/2: add_anchored_spring_unchecked adds nothing (G bit for bit) and the explicit
//   spring alone never lets E grow.
TEST(Contact, AnchoredSpringIsExplicitOnlyWithinItsDampingBound) {
  const double K = 26693.66, T = 2e-3, rho = 0.5e-3, delta0 = 1e-3;
  const Vec3 g = Vec3::Zero();
  const AnchoredSpring held{Vec3::Zero(), 1.0};
  auto contact_of = [&](const ProxyState& s) {
    const Vec3 n = (g - s.pose.x).normalized();
    Contact c;
    c.n = n;
    c.x_o = g - rho * n;
    c.r = s.pose.R.transpose() * (-rho * n);
    c.depth = (g - s.pose.x).norm();
    c.stiffness = K;
    return c;
  };
  AffineWrench push;
  push.f0 << 0.0, 0.0, -K * delta0, 0.0, 0.0, 0.0;
  for (const double mass : {0.005, 0.05, 0.5}) {
    ProxyParams p;
    p.mass = mass;
    p.inertia = Mat3::Identity() * 1e-5;
    // Above the minimum -1/2 K delta_0^2 (at c = -delta_0 e_z, at rest).
    auto energy = [&](const ProxyState& s) {
      const Vec3 c = s.pose.x;
      return 0.5 * p.mass * s.V.head<3>().squaredNorm() + 0.5 * K * (g - c).squaredNorm() +
             K * delta0 * c.z() + 0.5 * K * delta0 * delta0;
    };
    for (const double b_ratio : {0.9, 1.1}) {
      p.damping_lin = b_ratio * 0.5 * K * T;
      for (const bool add : {false, true}) {
        ProxyState s;
        s.pose.x = Vec3(0.1e-3, 0.0, -delta0);
        const double E0 = energy(s);
        double E = E0, worst_rise = 0.0;
        for (int k = 0; k < 2000 && E < 1e6 * E0; ++k) {
          const Contact c = contact_of(s);
          const std::span<const Contact> set(&c, 1);
          AffineWrench F = contact_wrench_unchecked(set, s.pose, T, Scheme::kMidpoint);
          const Mat6 G_before = F.G;
          if (add) {
            add_anchored_spring_unchecked(&F, set, s.pose, T, Scheme::kMidpoint, held,
                                          p.damping_lin, 0.0);
            if (b_ratio > 1.0) {
              ASSERT_EQ(F.G, G_before);  // within the bound: nothing added
            }
          }
          PmiSystem sys = pmi_inertia_system_unchecked(p, s, T);
          sys.add(F);
          sys.add(push);
          Vec6 V_hat;
          ASSERT_TRUE(pmi_try_solve(sys, &V_hat));
          s = pmi_advance_unchecked(s, V_hat, T);
          const double E1 = energy(s);
          worst_rise = std::max(worst_rise, (E1 - E) / E0);
          E = E1;
        }
        std::printf("m %.3f kg, b = %.1f K T/2, across n %s: E_end / E0 = %.3e, worst rise %.2e\n",
                    mass, b_ratio, add ? "bounded" : "explicit", E / E0, worst_rise);
        if (add || b_ratio > 1.0) {
          EXPECT_LE(worst_rise, 1e-9) << mass << " " << b_ratio << " " << add;
          EXPECT_LE(E, E0 * (1.0 + 1e-9)) << mass << " " << b_ratio << " " << add;
        } else {
          EXPECT_GT(E, 10.0 * E0) << mass;
        }
      }
    }
  }
}

// The anchored spring's damping b_t bounds the centre's mobility across n, and the split: a free
// anchor (h = 0) or the explicit scheme adds nothing; a held one adds -(K - 2 b_t/T) T/2 P on the
// translation when the centre is at the proxy origin.
TEST(Contact, AnchoredSpringAddsOnlyTheExcessOverTheBound) {
  EXPECT_EQ(anchored_spring_damping(Vec3::Zero(), 3.0, 0.0), 3.0);
  EXPECT_EQ(anchored_spring_damping(Vec3(0, 0, 1e-3), 3.0, 0.0), 0.0);
  EXPECT_EQ(anchored_spring_damping(Vec3::Zero(), 0.0, 1.0), 0.0);
  EXPECT_NEAR(anchored_spring_damping(Vec3(0, 0, 2e-3), 3.0, 4e-6), 1.0 / (1.0 / 3.0 + 1.0), 1e-15);
  Pose proxy;
  Contact c;
  c.n = Vec3(1.0, 2.0, 2.0) / 3.0;
  c.r = -0.5e-3 * c.n;
  c.x_o = c.r + 1e-4 * c.n;
  c.stiffness = 12000.0;
  c.damping = 5.0;
  const double T = 1e-3, b = 2.0;
  const std::span<const Contact> set(&c, 1);
  const Mat3 P = Mat3::Identity() - c.n * c.n.transpose();
  for (const double h : {0.0, 0.5, 1.0}) {
    for (const Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      const AffineWrench F0 = contact_wrench_unchecked(set, proxy, T, scheme);
      AffineWrench F = F0;
      add_anchored_spring_unchecked(&F, set, proxy, T, scheme, AnchoredSpring{Vec3::Zero(), h},
                                    b, 0.0);
      if (h == 0.0 || scheme == Scheme::kExplicit) {
        EXPECT_EQ(F.G, F0.G) << h;
        continue;
      }
      const Mat3 want = -(0.5 * T * (h * 12000.0 - 2.0 * b / T)) * P;
      EXPECT_LE(((F.G - F0.G).topLeftCorner<3, 3>() - want).cwiseAbs().maxCoeff(), 1e-12) << h;
      EXPECT_EQ(F.f0, F0.f0);
    }
  }
}

TEST(Contact, BadInputThrowsNamingTheField) {
  std::vector<Contact> set(2);
  set[0].stiffness = 1e3;
  set[1].weight = -1.0;
  EXPECT_NE(error_of([&] { contact_weights(set); }).find("contacts[1].weight"), std::string::npos);
  set[1].weight = std::nan("");
  EXPECT_NE(error_of([&] { contact_weights(set); }).find("contacts[1].weight"), std::string::npos);
  set[1].weight = 1.0;
  set[1].n = Vec3(0, 0, 2);
  EXPECT_NE(
      error_of([&] { contact_wrench(set, Pose{}, 1e-3, Scheme::kMidpoint); }).find("contacts[1].n"),
      std::string::npos);
  set[1].n = Vec3::UnitZ();
  set[0].stiffness = -5.0;
  EXPECT_NE(error_of([&] {
              contact_wrench(set, Pose{}, 1e-3, Scheme::kMidpoint);
            }).find("contacts[0].stiffness"),
            std::string::npos);
  set[0].stiffness = 1e3;
  set[0].damping = -1.0;
  EXPECT_NE(error_of([&] {
              contact_wrench(set, Pose{}, 1e-3, Scheme::kMidpoint);
            }).find("contacts[0].damping"),
            std::string::npos);
  set[0].damping = 0.0;
  EXPECT_NE(
      error_of([&] { contact_wrench(set, Pose{}, 0.0, Scheme::kMidpoint); }).find("tick length T"),
      std::string::npos);
  EXPECT_EQ(error_of([&] { contact_wrench(set, Pose{}, 1e-3, Scheme::kMidpoint); }),
            "(no InputError)");
}

}  // namespace
}  // namespace dentsim
