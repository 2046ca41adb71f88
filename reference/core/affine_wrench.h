// Forces on the proxy that are affine in the velocity they are evaluated at, and the PMI linear
// system they assemble into.
//
// Every force element of the proxy (virtual coupling (4.5), passive-decomposition feed-forward
// (4.7), penalty contact (2.16)/(2.19), friction (2.21)) is written as
//     F(V) = f0 + G V,
// a wrench [f (world); tau (body)] affine in a twist V. PMI evaluates it at the midpoint velocity
// V = V_hat_k (thesis (2.7)); the explicit-Euler baseline evaluates it at V = V_k. With the inertia
// terms (4.2) the PMI proxy update is the single 6x6 linear solve (4.9):
//     (M 2/T + B + C_k - sum G) V_hat = M 2/T V_k + sum f0.
#pragma once

#include "reference/core/types.h"

namespace dentsim {

// Which velocity an affine force is evaluated at.
enum class Scheme {
  kMidpoint,   // PMI: at V_hat_k, with the T/2 midpoint terms of the springs (2.7), (2.13), (2.16)
  kExplicit,   // explicit Euler: at V_k, springs at their value at t_k (no T/2 terms)
};

struct AffineWrench {
  Vec6 f0 = Vec6::Zero();
  Mat6 G = Mat6::Zero();

  Vec6 at(const Vec6& V) const { return f0 + G * V; }
  AffineWrench& operator+=(const AffineWrench& o) {
    f0 += o.f0;
    G += o.G;
    return *this;
  }
};

inline AffineWrench operator+(AffineWrench a, const AffineWrench& b) { return a += b; }

// The PMI system A V_hat = b of (4.9).
struct PmiSystem {
  Mat6 A = Mat6::Zero();
  Vec6 b = Vec6::Zero();

  // Adds a force F(V_hat) = f0 + G V_hat to the right-hand side of (4.2).
  void add(const AffineWrench& F) {
    A -= F.G;
    b += F.f0;
  }
};

}  // namespace dentsim
