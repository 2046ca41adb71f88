// Random friction cases (the friction solve's arguments, validation/friction_states.h) for the
// property tests of reference/friction.h (tests/reference/friction_test.cc) and the differential
// test of its fast twin (tests/fast/friction_test.cc).
#pragma once

#include <cmath>
#include <random>

#include "reference/contact.h"
#include "reference/core/so3.h"
#include "tests/support/random.h"
#include "validation/friction_states.h"

namespace dentsim::testing {

// A vector with entries uniform in [-scale, scale).
template <class Rng>
Vec3 random_vec(Rng& rng, double scale) {
  return Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)) * scale;
}

// A random PMI-like system: A = M 2/T + coupling (K_vc T/2 + B_vc, SPD) + proxy damping
// + gyroscopic C_k (skew), b random; the contact wrench of a random set of 1-4 members (one case
// in ten with every member outside the tooth) is added to it; mu in [0.05, 1.5).
template <class Rng>
FrictionState random_friction_case(Rng& rng) {
  FrictionState rc;
  const double T = uniform(rng, 1e-4, 2e-3);
  const double m = uniform(rng, 0.01, 0.5);
  Mat3 L;
  L << random_vec(rng, 1e-5), random_vec(rng, 1e-5), random_vec(rng, 1e-5);
  const Mat3 J = L * L.transpose() + uniform(rng, 1e-6, 1e-4) * Mat3::Identity();
  const Mat6 M = block_diag(m * Mat3::Identity(), J);
  const Mat6 Kvc =
      block_diag(uniform(rng, 0, 2000) * Mat3::Identity(), uniform(rng, 0, 1) * Mat3::Identity());
  const Mat6 Bvc =
      block_diag(uniform(rng, 0, 5) * Mat3::Identity(), uniform(rng, 0, 0.01) * Mat3::Identity());
  const Vec3 w_k = random_vec(rng, 5.0);
  Mat6 C = Mat6::Zero();
  C.bottomRightCorner<3, 3>() = -skew(J * w_k);  // C_k = diag(0, -S(J w_k))   (2.8)
  // Velocities and loads over several decades so that sticking and sliding both occur.
  const double v_scale = std::pow(10.0, uniform(rng, -5.0, -0.5));
  const double load = std::pow(10.0, uniform(rng, -2.0, 1.0));
  const Vec6 V_k = stack(random_vec(rng, v_scale), w_k * (v_scale / 0.3));
  rc.sys.A = M * (2.0 / T) + Kvc * (T / 2) + Bvc + C;
  rc.sys.b = M * (2.0 / T) * V_k + stack(random_vec(rng, load), random_vec(rng, 0.01 * load));
  rc.proxy = Pose{random_vec(rng, 0.05), exp_so3(random_unit(rng) * uniform(rng, 0, 3))};
  const Vec3 n0 = random_unit(rng);
  const int count = 1 + static_cast<int>(rng() % 4);
  const bool separated = rng() % 10 == 0;  // every member outside the tooth
  for (int i = 0; i < count; ++i) {
    Contact c;
    c.n = (n0 + random_vec(rng, 0.3)).normalized();
    c.r = random_vec(rng, 0.01);
    const double depth = separated ? uniform(rng, -2e-4, 0.0) : uniform(rng, -2e-4, 1e-3);
    c.x_o = rc.proxy.x + rc.proxy.R * c.r + depth * c.n;
    c.stiffness = uniform(rng, 1e2, 5e4);
    c.damping = uniform(rng, 0.0, 10.0);
    c.weight = uniform(rng, 0.0, 1.0);
    rc.contacts.push_back(c);
  }
  rc.normal = contact_wrench(rc.contacts, rc.proxy, T, Scheme::kMidpoint);
  rc.sys.add(rc.normal);
  rc.fp.enabled = true;
  rc.fp.mu = uniform(rng, 0.05, 1.5);
  return rc;
}

}  // namespace dentsim::testing
