// Tests for fast/decomposition.h: the decomposition's feed-forward (4.7) on its block structure
// against the reference's decompose_locked + pd_feedforward (reference/decomposition.h), on random
// device inertias (condition numbers up to 1e4), poses, proxy inertias (isotropic and general),
// diagonal tools (the presets and random ones), velocities, observer wrenches and contact terms.
//
// Tolerance (docs/tolerance_policy.md items 9 and 2): every output within 1e-10 relative to the
// scale of the terms it sums (an output that cancels, where phi is near I, is compared at the
// scale of what cancelled; absolute 1e-15 near zero); the signal guard (item 5) checks the outputs
// are far from zero. Seeds fixed and printed.
#include "fast/decomposition.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "fast/phantom/phantom_model.h"
#include "reference/core/so3.h"
#include "reference/phantom/phantom_params.h"
#include "reference/tick.h"
#include "reference/tools.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;

double uni(Rng& rng, double a, double b) { return testing::uniform(rng, a, b); }

Mat3 random_rotation(Rng& rng) { return exp_so3(testing::random_unit(rng) * uni(rng, 0.0, 3.1)); }

Mat6 random_matrix(Rng& rng) {
  Mat6 A;
  for (int i = 0; i < 36; ++i) A(i) = uni(rng, -1.0, 1.0);
  return A;
}

// A symmetric positive definite 6x6 with eigenvalues from `lo` to `hi`.
Mat6 random_spd(Rng& rng, double lo, double hi) {
  const Eigen::HouseholderQR<Mat6> qr(random_matrix(rng));
  const Mat6 U = qr.householderQ();
  Vec6 e;
  for (int i = 0; i < 6; ++i) e(i) = std::exp(uni(rng, std::log(lo), std::log(hi)));
  return U * e.asDiagonal() * U.transpose();
}

// A proxy of mass 1 g - 1 kg and inertia 1e-6 - 1e-4 kg m^2, isotropic (j I) or general (SPD).
ProxyParams random_proxy(Rng& rng, bool isotropic) {
  ProxyParams proxy;
  proxy.mass = std::pow(10.0, uni(rng, -3.0, 0.0));
  if (isotropic) {
    proxy.inertia = Mat3::Identity() * std::pow(10.0, uni(rng, -6.0, -4.0));
  } else {
    const Mat6 S = random_spd(rng, 1e-6, 1e-4);
    proxy.inertia = S.topLeftCorner<3, 3>();
  }
  return proxy;
}

TEST(FastDecomposition, FeedforwardAgreesWithTheReference) {
  constexpr unsigned kSeed = 30038;
  Rng rng(kSeed);
  double worst = 0.0, worst_isotropic = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    SCOPED_TRACE("seed " + std::to_string(kSeed) + " trial " + std::to_string(trial));
    const Mat6 M1 = random_spd(rng, 1e-2, 1e2);
    const ProxyParams proxy = random_proxy(rng, trial % 2 == 0);
    ToolDynamics tool;
    if (trial % 3 == 0) {
      tool = tool_preset(tool_preset_names()[(trial / 3) % tool_preset_names().size()]);
    } else {
      Vec6 md, dd;
      for (int i = 0; i < 6; ++i) {
        md(i) = std::pow(10.0, uni(rng, -5.0, 1.0));
        dd(i) = trial % 5 == 1 ? 0.0 : std::pow(10.0, uni(rng, -4.0, 1.0));
      }
      tool.M_d = md.asDiagonal();
      tool.D_d = dd.asDiagonal();
    }
    ASSERT_TRUE(fast::pd_tool_is_diagonal(tool));
    const Mat3 R1 = random_rotation(rng), R2 = random_rotation(rng);
    Vec6 V1, F1_hat;
    for (int i = 0; i < 6; ++i) V1(i) = uni(rng, -1.0, 1.0), F1_hat(i) = uni(rng, -5.0, 5.0);
    AffineWrench F2;  // zero in free space (every fourth trial), a contact's terms otherwise
    if (trial % 4 != 0) {
      for (int i = 0; i < 6; ++i) F2.f0(i) = uni(rng, -5.0, 5.0);
      F2.G = -random_spd(rng, 1e-2, 1e4);
    }

    Decomposition dec;
    ASSERT_TRUE(decompose_locked(M1, proxy.M(), R1, R2, &dec));
    const Eigen::LLT<Mat6> Md_llt(tool.M_d);
    const PdFeedforward ref = pd_feedforward(dec, Md_llt, tool.D_d, V1, F1_hat, F2);
    PdFeedforward got;
    ASSERT_TRUE(fast::pd_feedforward_diagonal(M1, proxy, tool, R1, R2, V1, F1_hat, F2, &got));
    if (trial % 4 == 0) {
      // F2 = 0 known to the caller (a free tick): the products with F2 left out, the same
      // doubles (x - 0 = x, x + 0 = x).
      PdFeedforward f;
      ASSERT_TRUE(fast::pd_feedforward_diagonal(M1, proxy, tool, R1, R2, V1, F1_hat, F2, &f,
                                                {.contact_free = true}));
      for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(f.T1.f0(i), got.T1.f0(i));
        EXPECT_EQ(f.T2.f0(i), got.T2.f0(i));
        for (int k = 0; k < 6; ++k) {
          EXPECT_EQ(f.T1.G(i, k), got.T1.G(i, k));
          EXPECT_EQ(f.T2.G(i, k), got.T2.G(i, k));
        }
      }
    }
    {
      // M1 exactly symmetric (as inertia_at_tool gives it): the symmetrisation left out, the
      // same doubles as with it (0.5 (x + x) = x).
      const Mat6 Ms = 0.5 * (M1 + M1.transpose());
      PdFeedforward with, without;
      ASSERT_TRUE(fast::pd_feedforward_diagonal(Ms, proxy, tool, R1, R2, V1, F1_hat, F2, &with));
      ASSERT_TRUE(fast::pd_feedforward_diagonal(Ms, proxy, tool, R1, R2, V1, F1_hat, F2, &without,
                                                {.symmetric_M1 = true}));
      EXPECT_EQ(with.T1.f0, without.T1.f0);
      EXPECT_EQ(with.T1.G, without.T1.G);
      EXPECT_EQ(with.T2.f0, without.T2.f0);
      EXPECT_EQ(with.T2.G, without.T2.G);
    }
    if (trial % 2 == 0) {
      // The isotropic proxy's path (J = j I) against the general path on the same inputs (J
      // perturbed by 1e-300 off the diagonal): they differ only by the general path's round-off
      // of Q^T J Q off j I (order eps j): within 1e-12 of the outputs' scale.
      ProxyParams general = proxy;
      general.inertia(0, 1) = general.inertia(1, 0) = 1e-300;
      PdFeedforward g;
      ASSERT_TRUE(fast::pd_feedforward_diagonal(M1, general, tool, R1, R2, V1, F1_hat, F2, &g));
      const double s = std::max({g.T1.f0.cwiseAbs().maxCoeff(), g.T2.f0.cwiseAbs().maxCoeff(),
                                 g.T1.G.cwiseAbs().maxCoeff(), g.T2.G.cwiseAbs().maxCoeff()});
      const double e = std::max({(got.T1.f0 - g.T1.f0).cwiseAbs().maxCoeff(),
                                 (got.T2.f0 - g.T2.f0).cwiseAbs().maxCoeff(),
                                 (got.T1.G - g.T1.G).cwiseAbs().maxCoeff(),
                                 (got.T2.G - g.T2.G).cwiseAbs().maxCoeff()});
      EXPECT_LE(e, 1e-12 * s);
      worst_isotropic = std::max(worst_isotropic, e / s);
    }

    // Each output is a difference, T1 = (I - phi^T) X - F1_hat and T2 = E phi^T X - F2, which
    // cancels where phi is near I: its scale is that of the terms summed (item 2), |X| (1 +
    // |phi|) and the wrench subtracted, X = M_L M1^-1 (T1 + F1_hat) (decomposition.h's identity).
    const Mat6 back = dec.M_L * M1.inverse();
    const double grow = 1.0 + dec.phi.cwiseAbs().rowwise().sum().maxCoeff();
    const double s0 = std::max({(back * (ref.T1.f0 + F1_hat)).cwiseAbs().maxCoeff() * grow,
                                F1_hat.cwiseAbs().maxCoeff(), F2.f0.cwiseAbs().maxCoeff()});
    const double sG = std::max((back * ref.T1.G).cwiseAbs().maxCoeff() * grow,
                               F2.G.cwiseAbs().maxCoeff());
    const auto err = [](const auto& a, const auto& b, double scale) {
      const double e = (a - b).cwiseAbs().maxCoeff();
      return e <= 1e-15 ? 0.0 : e / scale;
    };
    const double errs[] = {err(got.T1.f0, ref.T1.f0, s0), err(got.T1.G, ref.T1.G, sG),
                           err(got.T2.f0, ref.T2.f0, s0), err(got.T2.G, ref.T2.G, sG)};
    for (const double e : errs) {
      EXPECT_LE(e, 1e-10);
      worst = std::max(worst, e);
    }
    // Signal guard: the outputs are far from zero.
    ASSERT_GT(ref.T1.f0.cwiseAbs().maxCoeff(), 1e-3);
    // (T1.G = 0 exactly without damping and contact: that case checks zero against zero.)
    if (trial % 4 != 0 || !tool.D_d.isZero(0.0)) {
      ASSERT_GT(ref.T1.G.cwiseAbs().maxCoeff(), 1e-6);
    }
  }
  std::printf("fast vs reference feed-forward: worst relative error %.2e\n", worst);
  std::printf("isotropic vs general proxy path: worst relative difference %.2e\n",
              worst_isotropic);
}

// T1 kept factored (pd_feedforward_diagonal_factored: T1(V) = M1 W(V) - F1_hat) against T1 formed
// (pd_feedforward_diagonal): T2 the same doubles; T1 at random velocities within the derived
// bound 2 gamma_14 (|M1| (|W0| + |WG| |V|) + |F1_hat|) entrywise (fast/decomposition.h), free
// and contact ticks, the presets' and random diagonal tools.
TEST(FastDecomposition, FactoredT1IsTheFormedT1WithinItsRoundOffBound) {
  constexpr unsigned kSeed = 5103;
  Rng rng(kSeed);
  constexpr double u = 0x1p-53;
  const double gamma14 = 14 * u / (1 - 14 * u);
  double worst = 0.0;
  long checked = 0, nonzero_diff = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    SCOPED_TRACE("seed " + std::to_string(kSeed) + " trial " + std::to_string(trial));
    Mat6 M1 = random_spd(rng, 1e-2, 1e2);
    M1 = (0.5 * (M1 + M1.transpose())).eval();  // exactly symmetric, as inertia_at_tool's
    const ProxyParams proxy = random_proxy(rng, trial % 2 == 0);
    ToolDynamics tool = tool_preset(tool_preset_names()[trial % tool_preset_names().size()]);
    if (trial % 3 == 1) {
      Vec6 md, dd;
      for (int i = 0; i < 6; ++i) {
        md(i) = std::pow(10.0, uni(rng, -5.0, 1.0));
        dd(i) = std::pow(10.0, uni(rng, -4.0, 1.0));
      }
      tool.M_d = md.asDiagonal();
      tool.D_d = dd.asDiagonal();
    }
    const Mat3 R1 = random_rotation(rng), R2 = random_rotation(rng);
    Vec6 V1, F1_hat;
    for (int i = 0; i < 6; ++i) V1(i) = uni(rng, -1.0, 1.0), F1_hat(i) = uni(rng, -5.0, 5.0);
    AffineWrench F2;
    const bool free_tick = trial % 2 == 0;
    if (!free_tick) {
      for (int i = 0; i < 6; ++i) F2.f0(i) = uni(rng, -5.0, 5.0);
      F2.G = -random_spd(rng, 1e-2, 1e4);
    }
    const fast::FeedforwardKnown known{free_tick, true};
    AffineWrench T1, T2, W, T2f;
    ASSERT_TRUE(fast::pd_feedforward_diagonal(M1, proxy, tool, R1, R2, V1, F1_hat, F2, &T1, &T2,
                                              known));
    ASSERT_TRUE(fast::pd_feedforward_diagonal_factored(M1, proxy, tool, R1, R2, V1, F1_hat, F2,
                                                       &W, &T2f, known));
    EXPECT_EQ(T2.f0, T2f.f0);
    EXPECT_EQ(T2.G, T2f.G);
    for (int k = 0; k < 20; ++k) {
      Vec6 V;
      for (int i = 0; i < 6; ++i) V(i) = uni(rng, -1.0, 1.0) * std::pow(10.0, uni(rng, -3.0, 1.0));
      const Vec6 formed = T1.at(V);
      const Vec6 w = W.at(V);
      const Vec6 factored = M1 * w - F1_hat;
      const Vec6 scale =
          M1.cwiseAbs() * (W.f0.cwiseAbs() + W.G.cwiseAbs() * V.cwiseAbs()) + F1_hat.cwiseAbs();
      for (int i = 0; i < 6; ++i) {
        const double e = std::abs(formed(i) - factored(i));
        EXPECT_LE(e, 2 * gamma14 * scale(i)) << i;
        worst = std::max(worst, e / scale(i));
        nonzero_diff += e != 0.0 ? 1 : 0;
        ++checked;
      }
    }
  }
  std::printf("factored vs formed T1: worst |diff| / scale %.2e (bound %.2e), %ld of %ld differ\n",
              worst, 2 * gamma14, nonzero_diff, checked);
  EXPECT_GT(nonzero_diff, 0);  // the two orders do differ: the bound is what is checked
}

// M1 = J1^T M J1 (fast/decomposition.h inertia_at_tool) against the reference's (J1^T M) J1: each
// entry within the derived bound 2 (2 gamma_6 + gamma_6^2) (|J1|^T |M| |J1|)(i, j) < 25 u
// (|J1|^T |M| |J1|)(i, j), u = 2^-53, and exactly symmetric. J1 the inverse of the Phantom's J_t at
// random joint states (the tick's own) and random matrices; M the Phantom's mass matrix there and
// random SPD matrices of condition up to 1e6.
TEST(FastDecomposition, InertiaAtToolAgreesWithTheReferenceWithinItsRoundOffBound) {
  constexpr unsigned kSeed = 46030;
  Rng rng(kSeed);
  const fast::PhantomModel device(default_phantom_params());
  const double u = std::ldexp(1.0, -53);
  double worst = 0.0;  // |got - ref| / (u (|J1|^T |M| |J1|)(i, j)), largest over every entry
  int nonzero = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    SCOPED_TRACE("seed " + std::to_string(kSeed) + " trial " + std::to_string(trial));
    Mat6 J1, M;
    if (trial % 2 == 0) {
      Vec6 q, qd = Vec6::Zero();
      for (int i = 0; i < 6; ++i) q(i) = uni(rng, -0.8, 0.8);
      DeviceTerms t;
      device.terms(q, qd, false, t);
      J1 = t.J_t.inverse();
      M = t.M;
    } else {
      J1 = random_matrix(rng) * std::pow(10.0, uni(rng, -2.0, 2.0));
      M = random_spd(rng, 1e-4, 1e2);
    }
    ASSERT_TRUE(J1.allFinite());
    Mat6 got;
    fast::inertia_at_tool(J1, M, &got);
    const Mat6 ref = J1.transpose() * M * J1;
    const Mat6 scale = J1.cwiseAbs().transpose() * M.cwiseAbs() * J1.cwiseAbs();
    for (int j = 0; j < 6; ++j) {
      for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(got(i, j), got(j, i));
        const double e = std::abs(got(i, j) - ref(i, j));
        EXPECT_LE(e, 25.0 * u * scale(i, j)) << "entry " << i << "," << j;
        worst = std::max(worst, e / (u * scale(i, j)));
        nonzero += got(i, j) != 0.0 ? 1 : 0;
      }
    }
  }
  EXPECT_EQ(nonzero, 4000 * 36);  // signal guard: no entry is a zero compared against a zero
  std::printf("inertia_at_tool vs (J1^T M) J1: worst %.2f u of |J1|^T |M| |J1| (bound 25)\n",
              worst);
}

TEST(FastDecomposition, LockedInertiaNotPositiveDefiniteFailsAsTheReference) {
  Mat6 M1 = Mat6::Identity();
  M1(0, 0) = -10.0;  // M_L = M1 + E^T M2 E not positive definite
  const ProxyParams proxy;
  const ToolDynamics tool = tool_preset("handpiece");
  Decomposition dec;
  EXPECT_FALSE(decompose_locked(M1, proxy.M(), Mat3::Identity(), Mat3::Identity(), &dec));
  PdFeedforward out;
  EXPECT_FALSE(fast::pd_feedforward_diagonal(M1, proxy, tool, Mat3::Identity(), Mat3::Identity(),
                                             Vec6::Zero(), Vec6::Zero(), AffineWrench{}, &out));
}

TEST(FastDecomposition, OnlyDiagonalToolsTakeTheSpecialisedPath) {
  ToolDynamics tool = tool_preset("explorer");
  EXPECT_TRUE(fast::pd_tool_is_diagonal(tool));
  tool.M_d(0, 1) = tool.M_d(1, 0) = 1e-3;
  EXPECT_FALSE(fast::pd_tool_is_diagonal(tool));
  tool = tool_preset("explorer");
  tool.D_d(5, 2) = 1e-6;
  EXPECT_FALSE(fast::pd_tool_is_diagonal(tool));
}

// The fast tick reads the check from PipelineModel::tool_diagonal, decided once at setup: it is
// pd_tool_is_diagonal of the tool, for every preset and for tools off the diagonal in M_d or D_d
// (one entry of 1e-300 is enough to leave the specialised path).
TEST(FastDecomposition, SetupDecidesTheDiagonalToolOnceAsPdToolIsDiagonal) {
  const fast::PhantomModel device(default_phantom_params());
  std::vector<ToolDynamics> tools;
  for (const std::string& name : tool_preset_names()) tools.push_back(tool_preset(name));
  ToolDynamics t = tool_preset("handpiece");
  t.M_d(2, 4) = t.M_d(4, 2) = 1e-300;
  tools.push_back(t);
  t = tool_preset("handpiece");
  t.D_d(0, 3) = -1e-300;
  tools.push_back(t);
  int diagonal = 0;
  for (const ToolDynamics& tool : tools) {
    PipelineConfig config;
    config.method = Method::kPmiPd;
    config.observer_gain = Vec6::Constant(100.0);  // pmi-pd needs the observer
    config.tool = tool;
    const PipelineModel m = make_pipeline_model(device, config);
    EXPECT_EQ(m.tool_diagonal, fast::pd_tool_is_diagonal(tool)) << tool.name;
    diagonal += m.tool_diagonal ? 1 : 0;
  }
  EXPECT_EQ(diagonal, int(tools.size()) - 2);  // the presets are diagonal, the two changed not
}

}  // namespace
}  // namespace dentsim
