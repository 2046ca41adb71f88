// Tests for reference/explicit_euler.h: the explicit-Euler baseline proxy ("standard" virtual
// coupling, thesis §4.2), against closed forms and against PMI with the same coupling.
// Tolerances: docs/tolerance_policy.md (round-off bounds state c and the scale; discretisation
// orders are checked by the error ratio when T is halved).
#include "reference/explicit_euler.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "reference/coupling.h"
#include "reference/pmi.h"

namespace dentsim {
namespace {

ProxyParams test_params() {
  ProxyParams p;
  p.mass = 0.05;
  p.inertia = Vec3(1.0e-5, 2.0e-5, 3.0e-5).asDiagonal();
  return p;
}

TEST(ExplicitEuler, OneTickByHand) {
  ProxyParams p = test_params();
  p.damping_lin = 0.5;
  p.damping_ang = 1e-5;
  p.gyroscopic = true;
  ProxyState s;
  s.pose.x = Vec3(0.01, 0.0, -0.01);
  s.pose.R = exp_so3(Vec3(0.1, 0.2, 0.3));
  s.V << 0.2, -0.1, 0.0, 1.0, 2.0, 3.0;
  s.V_hat_prev << 9, 9, 9, 9, 9, 9;
  Vec6 F;
  F << 1.0, 0.0, -0.5, 1e-4, 0.0, -2e-4;
  const double T = 1e-3;
  const ProxyState n = explicit_euler_advance(p, s, F, T);
  // v: 0.2 + (1e-3 / 0.05) (1 - 0.5 * 0.2) = 0.218; -0.1 + 0.02 (0.05) = -0.099; 0.02 (-0.5).
  EXPECT_NEAR(n.V(0), 0.218, 1e-15);
  EXPECT_NEAR(n.V(1), -0.099, 1e-15);
  EXPECT_NEAR(n.V(2), -0.010, 1e-15);
  // w x J w = (1,2,3) x (1,4,9)e-5 = (6,-6,2)e-5; tau - b_w w - w x Jw = (1e-4 - 1e-5 - 6e-5,
  // -2e-5 + 6e-5, -2e-4 - 3e-5 - 2e-5) = (3e-5, 4e-5, -2.5e-4); J^-1 of it = (3, 2, -8.3333).
  EXPECT_NEAR(n.V(3), 1.0 + T * 3.0, 1e-12);
  EXPECT_NEAR(n.V(4), 2.0 + T * 2.0, 1e-12);
  EXPECT_NEAR(n.V(5), 3.0 - T * 2.5e-4 / 3e-5, 1e-12);
  EXPECT_LT((n.pose.x - (s.pose.x + T * lin(s.V))).norm(), 1e-18);  // x_k+1 = x_k + T v_k
  EXPECT_LT((n.pose.R - s.pose.R * exp_so3(T * ang(s.V))).norm(), 1e-15);
  EXPECT_EQ(n.V_hat_prev, s.V);  // the device side sees V_k
}

TEST(ExplicitEuler, BadInputThrows) {
  const ProxyParams p = test_params();
  const ProxyState s;
  EXPECT_THROW(explicit_euler_advance(p, s, Vec6::Zero(), 0.0), InputError);
  Vec6 F = Vec6::Zero();
  F(3) = std::nan("");
  EXPECT_THROW(explicit_euler_advance(p, s, F, 1e-3), std::runtime_error);
}

// Torque-free body with the gyroscopic term: w^T (w x J w) = 0, so explicit Euler changes the
// kinetic energy by exactly T^2/2 wdot^T J wdot > 0 every tick (PMI: 0, pmi_test).
TEST(ExplicitEuler, FreeRigidBodyGainsExactlyTheEulerEnergyTerm) {
  ProxyParams p = test_params();
  p.gyroscopic = true;
  ProxyState s;
  s.V << 0.0, 0.0, 0.0, 3.0, 5.0, -2.0;
  const double T = 1e-3;
  const double ke0 = proxy_kinetic_energy(p, s.V);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 w = ang(s.V);
    const Vec3 wdot = -p.inertia.inverse() * w.cross(p.inertia * w);
    const double expected = 0.5 * T * T * wdot.dot(p.inertia * wdot);
    const double ke = proxy_kinetic_energy(p, s.V);
    s = explicit_euler_advance(p, s, Vec6::Zero(), T);
    const double dke = proxy_kinetic_energy(p, s.V) - ke;
    ASSERT_GT(dke, 0.0);
    ASSERT_NEAR(dke, expected, 1e-14 * ke) << "tick " << i;
  }
  std::printf("explicit Euler free body: KE grew by a factor %.6f in 1000 ticks\n",
              proxy_kinetic_energy(p, s.V) / ke0);
}

struct Oscillator {
  const char* name;
  CouplingGains g;
  ProxyState s0;
  double omega;  // natural frequency [rad/s]
};

// A proxy on the virtual coupling to a fixed device, coupling damping and proxy damping zero.
// Translation: m = 0.05 kg, k = 400 N/m -> omega = 89.44 rad/s. Rotation about the proxy's z axis
// (J_zz = 3e-5 kg m^2, k_w = 0.3 N m/rad -> omega = 100 rad/s): log(R2^T R1) = -phi z exactly, so
// it is a linear oscillator in phi too.
Oscillator translational() {
  Oscillator o{"translation", {}, {}, std::sqrt(400.0 / 0.05)};
  o.g = {400.0, 0.0, 0.0, 0.0};
  o.s0.pose.x = Vec3(0.002, 0.0, 0.0);
  return o;
}
Oscillator rotational() {
  Oscillator o{"rotation", {}, {}, std::sqrt(0.3 / 3e-5)};
  o.g = {0.0, 0.3, 0.0, 0.0};
  o.s0.pose.R = exp_so3(Vec3(0.0, 0.0, 0.01));  // stays < pi after 10 periods of growth
  return o;
}

double energy(const ProxyParams& p, const CouplingGains& g, const ProxyState& s) {
  return proxy_kinetic_energy(p, s.V) + coupling_potential(g, Pose{}, s.pose);
}

// Explicit Euler of m x'' = -k x maps (omega x, v) to sqrt(1 + (omega T)^2) times a rotation, so
// the energy is multiplied by exactly 1 + (omega T)^2 every tick: per period of n = round(2 pi /
// (omega T)) ticks, by (1 + (omega T)^2)^n. PMI with the same coupling conserves it.
TEST(ExplicitEuler, UndampedCouplingGainsEnergyEveryPeriodWherePmiDoesNot) {
  const ProxyParams p = test_params();
  const Pose device;  // fixed at the origin, identity orientation
  const Vec6 V1 = Vec6::Zero();
  for (const Oscillator& o : {translational(), rotational()}) {
    for (double T : {1e-4, 1e-3}) {
      const long n = std::lround(2.0 * std::numbers::pi / (o.omega * T));
      const double closed_form = std::pow(1.0 + o.omega * o.omega * T * T, static_cast<double>(n));
      ProxyState ee = o.s0, pmi = o.s0;
      const double E0 = energy(p, o.g, o.s0);
      double E_prev = E0, worst_pmi = 0.0;
      for (int period = 0; period < 10; ++period) {
        for (long i = 0; i < n; ++i) {
          // Both share coupling_proxy_wrench: kExplicit evaluated at V_k, kMidpoint solved by PMI.
          const Vec6 F = coupling_proxy_wrench(o.g, device, V1, ee, T, Scheme::kExplicit).at(ee.V);
          ee = explicit_euler_advance(p, ee, F, T);
          PmiSystem sys = pmi_inertia_system(p, pmi, T);
          sys.add(coupling_proxy_wrench(o.g, device, V1, pmi, T, Scheme::kMidpoint));
          pmi = pmi_advance(pmi, pmi_solve(sys), T);
          worst_pmi = std::max(worst_pmi, std::abs(energy(p, o.g, pmi) - E0) / E0);
        }
        const double E = energy(p, o.g, ee);
        const double growth = E / E_prev;
        if (period == 0) {
          std::printf(
              "%s, T = %.0e s: %ld ticks/period, explicit growth per period %.6f, "
              "closed form %.6f; PMI max rel energy error %.2e\n",
              o.name, T, n, growth, closed_form, worst_pmi);
        }
        EXPECT_GT(growth, 1.0);
        EXPECT_NEAR(growth / closed_form, 1.0, 0.01) << o.name << " T " << T;
        E_prev = E;
      }
      EXPECT_LT(worst_pmi, 1e-12) << o.name << " T " << T;
      std::printf("%s, T = %.0e s: after 10 periods explicit E/E0 = %.4f, PMI E/E0 - 1 = %.2e\n",
                  o.name, T, energy(p, o.g, ee) / E0, energy(p, o.g, pmi) / E0 - 1.0);
    }
  }
}

}  // namespace
}  // namespace dentsim
