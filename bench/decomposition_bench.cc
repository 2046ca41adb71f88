// Google Benchmark of the pmi-pd tick's decomposition step (assemble: M1 = J1^T M J1 is not
// timed): the reference's decompose_locked + pd_feedforward (reference/decomposition.h) against
// fast::pd_feedforward_diagonal (fast/decomposition.h), over 256 seeded Phantom states (M1 from
// fast::PhantomModel, random poses of device and proxy), the drill scene's proxy (0.05 kg,
// 1e-5 kg m^2) and handpiece tool; arg 0: free space (F2 = 0), 1: a contact's F2.
// Results and the command: docs/benchmarks.md "Free-space tick: what issue #30's fast/ work cut".
#include <benchmark/benchmark.h>

#include <Eigen/LU>
#include <random>
#include <vector>

#include "fast/decomposition.h"
#include "fast/dense6.h"
#include "fast/phantom/phantom_model.h"
#include "reference/core/so3.h"
#include "reference/tools.h"

namespace dentsim {
namespace {

struct PdState {
  Mat6 M1;
  Mat3 R1, R2;
  Vec6 V1, F1_hat;
  AffineWrench F2;
};

// The Phantom's terms at rest at a configuration drawn uniformly within its joint limits.
DeviceTerms random_phantom_terms(const PhantomParams& p, const fast::PhantomModel& model,
                                 std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Vec6 q;
  for (int j = 0; j < 6; ++j) q(j) = p.q_min_rad(j) + u(rng) * (p.q_max_rad(j) - p.q_min_rad(j));
  DeviceTerms t;
  model.terms(q, Vec6::Zero(), false, t);
  return t;
}

const std::vector<PdState>& pd_states(bool contact) {
  static const auto make = [](bool with_contact) {
    const PhantomParams p = default_phantom_params();
    const fast::PhantomModel model(p);
    std::mt19937_64 rng(30038);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<PdState> out(256);
    for (PdState& s : out) {
      const DeviceTerms t = random_phantom_terms(p, model, rng);
      const Mat6 J1 = t.J_t.partialPivLu().inverse();
      s.M1 = J1.transpose() * t.M * J1;
      s.R1 = t.pose.R;
      s.R2 = exp_so3(Vec3(u(rng), u(rng), u(rng)) * 0.1) * t.pose.R;
      for (int i = 0; i < 6; ++i) s.V1(i) = u(rng) - 0.5, s.F1_hat(i) = u(rng) - 0.5;
      if (with_contact) {
        const Vec3 n = Vec3(u(rng) - 0.5, u(rng) - 0.5, 1.0).normalized();
        s.F2.f0.head<3>() = 0.8 * n;
        s.F2.G.topLeftCorner<3, 3>() = -3000.0 * n * n.transpose();
      }
    }
    return out;
  };
  static const std::vector<PdState> kFree = make(false), kContact = make(true);
  return contact ? kContact : kFree;
}

ProxyParams drill_proxy() {
  ProxyParams proxy;
  proxy.mass = 0.05;
  proxy.inertia = Mat3::Identity() * 1e-5;
  return proxy;
}

void BM_PdFeedforwardReference(benchmark::State& state) {
  const std::vector<PdState>& s = pd_states(state.range(0) != 0);
  const ProxyParams proxy = drill_proxy();
  const ToolDynamics tool = tool_preset("handpiece");
  const Eigen::LLT<Mat6> Md_llt(tool.M_d);
  const Mat6 M2 = proxy.M();
  std::size_t k = 0;
  for (auto _ : state) {
    Decomposition dec;
    const PdState& x = s[k];
    benchmark::DoNotOptimize(decompose_locked(x.M1, M2, x.R1, x.R2, &dec));
    PdFeedforward pd = pd_feedforward(dec, Md_llt, tool.D_d, x.V1, x.F1_hat, x.F2);
    benchmark::DoNotOptimize(pd);
    k = (k + 1) % s.size();
  }
}

void BM_PdFeedforwardFast(benchmark::State& state) {
  const std::vector<PdState>& s = pd_states(state.range(0) != 0);
  const ProxyParams proxy = drill_proxy();
  const ToolDynamics tool = tool_preset("handpiece");
  std::size_t k = 0;
  for (auto _ : state) {
    const PdState& x = s[k];
    PdFeedforward pd;
    benchmark::DoNotOptimize(
        fast::pd_feedforward_diagonal(x.M1, proxy, tool, x.R1, x.R2, x.V1, x.F1_hat, x.F2, &pd));
    benchmark::DoNotOptimize(pd);
    k = (k + 1) % s.size();
  }
}

BENCHMARK(BM_PdFeedforwardReference)->Arg(0)->Arg(1);
BENCHMARK(BM_PdFeedforwardFast)->Arg(0)->Arg(1);

// J1 = J_t^-1 (the device_terms stage) over 256 seeded Phantom Jacobians: Eigen's partial-pivoting
// LU and inverse (the reference's) against fast/dense6.h's.
const std::vector<Mat6>& phantom_jacobians() {
  static const std::vector<Mat6> out = [] {
    const PhantomParams p = default_phantom_params();
    const fast::PhantomModel model(p);
    std::mt19937_64 rng(30040);
    std::vector<Mat6> js(256);
    for (Mat6& J : js) J = random_phantom_terms(p, model, rng).J_t;
    return js;
  }();
  return out;
}

void BM_JacobianInverseEigen(benchmark::State& state) {
  const std::vector<Mat6>& js = phantom_jacobians();
  std::size_t k = 0;
  for (auto _ : state) {
    const Eigen::PartialPivLU<Mat6> lu(js[k]);
    Mat6 inv = lu.inverse();
    benchmark::DoNotOptimize(inv);
    k = (k + 1) % js.size();
  }
}

void BM_JacobianInverseDense6(benchmark::State& state) {
  const std::vector<Mat6>& js = phantom_jacobians();
  std::size_t k = 0;
  for (auto _ : state) {
    fast::Lu6 lu;
    Mat6 inv;
    benchmark::DoNotOptimize(fast::lu6(js[k], &lu));
    fast::lu6_inverse(lu, &inv);
    benchmark::DoNotOptimize(inv);
    k = (k + 1) % js.size();
  }
}

BENCHMARK(BM_JacobianInverseEigen);
BENCHMARK(BM_JacobianInverseDense6);

}  // namespace
}  // namespace dentsim
