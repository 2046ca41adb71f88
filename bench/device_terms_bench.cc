// Google Benchmark of the Phantom's device terms (the servo tick's `device_terms` stage): the
// reference one-pass PhantomModel::terms, the fast twin fast::PhantomModel::terms (double; float
// as a time-vs-error point), and MuJoCo's mass matrix (mj_crb, mj_fullM) and bias (mj_rne) on the
// Phantom's MJCF for scale, all over the same 256 seeded states (joint box, qd up to 20 rad/s).
// Results and the command: docs/benchmarks.md, "Device terms: reference vs fast vs MuJoCo".
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <array>
#include <random>
#include <vector>

#include "fast/phantom/phantom_model.h"
#include "plant/mujoco_phantom.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

constexpr int kStates = 256;

struct State {
  Vec6 q, qd;
};

const std::vector<State>& states() {
  static const std::vector<State> s = [] {
    const PhantomParams p = default_phantom_params();
    std::mt19937_64 rng(14014);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<State> out(kStates);
    for (State& st : out) {
      for (int j = 0; j < 6; ++j) {
        st.q(j) = p.q_min_rad(j) + u(rng) * (p.q_max_rad(j) - p.q_min_rad(j));
        st.qd(j) = 20.0 * (2.0 * u(rng) - 1.0);
      }
    }
    return out;
  }();
  return s;
}

// terms() of `model` cycling through the states; arg 0: 1 = with the Jacobian rate.
template <typename Model>
void run_terms(benchmark::State& state) {
  static const Model model(default_phantom_params());
  const bool rate = state.range(0) != 0;
  const std::vector<State>& s = states();
  DeviceTerms t;
  int k = 0;
  for (auto _ : state) {
    model.terms(s[k].q, s[k].qd, rate, t);
    benchmark::DoNotOptimize(t);
    k = (k + 1) % kStates;
  }
  state.SetLabel(rate ? "with dJ_t/dt" : "without dJ_t/dt");
}

void BM_DeviceTermsReference(benchmark::State& state) { run_terms<PhantomModel>(state); }
void BM_DeviceTermsFast(benchmark::State& state) { run_terms<fast::PhantomModel>(state); }
void BM_DeviceTermsFastFloat(benchmark::State& state) { run_terms<fast::PhantomModelFloat>(state); }
BENCHMARK(BM_DeviceTermsReference)->Arg(0)->Arg(1);
BENCHMARK(BM_DeviceTermsFast)->Arg(0)->Arg(1);
BENCHMARK(BM_DeviceTermsFastFloat)->Arg(0)->Arg(1);

// The reference's separate calls M(q) and C(q, qd) (what the tick called before one pass).
void BM_ReferenceMassMatrix(benchmark::State& state) {
  static const PhantomModelD model(default_phantom_params());
  const std::vector<State>& s = states();
  int k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(model.M(s[k].q));
    k = (k + 1) % kStates;
  }
}
BENCHMARK(BM_ReferenceMassMatrix);

// MuJoCo on the Phantom's 8-dof tree (plant/mujoco_phantom.h), qpos = G q, qvel = G qd of
// the same states. Arg 0 selects what one iteration computes:
//   0: mj_crb alone (kinematics and com positions of one state computed beforehand)
//   1: mj_kinematics + mj_comPos + mj_crb + mj_fullM: the dense M from q
//   2: 1 + mj_comVel + mj_rne: M and the bias C qd + g (velocity products and gravity)
void BM_Mujoco(benchmark::State& state) {
  static MujocoPhantom phantom(default_phantom_params());
  const mjModel* m = phantom.model();
  mjData* d = phantom.data();
  const int what = static_cast<int>(state.range(0));
  const std::vector<State>& s = states();
  std::vector<std::vector<mjtNum>> qpos(kStates), qvel(kStates);
  for (int k = 0; k < kStates; ++k) {
    phantom.set_state(s[k].q, s[k].qd);
    qpos[k].assign(d->qpos, d->qpos + m->nq);
    qvel[k].assign(d->qvel, d->qvel + m->nv);
  }
  std::vector<mjtNum> dense(m->nv * m->nv), bias(m->nv);
  int k = 0;
  for (auto _ : state) {
    if (what == 0) {
      mj_crb(m, d);
    } else {
      mju_copy(d->qpos, qpos[k].data(), m->nq);
      mju_copy(d->qvel, qvel[k].data(), m->nv);
      mj_kinematics(m, d);
      mj_comPos(m, d);
      mj_crb(m, d);
      mj_fullM(m, dense.data(), d->qM);
      if (what == 2) {
        mj_comVel(m, d);
        mj_rne(m, d, 0, bias.data());
      }
    }
    benchmark::DoNotOptimize(d->qM[0]);
    benchmark::DoNotOptimize(dense.data());
    benchmark::DoNotOptimize(bias.data());
    k = (k + 1) % kStates;
  }
  static const char* const kLabels[] = {"mj_crb", "kinematics+comPos+crb+fullM",
                                        "kinematics+comPos+crb+fullM+comVel+rne"};
  state.SetLabel(kLabels[what]);
}
BENCHMARK(BM_Mujoco)->Arg(0)->Arg(1)->Arg(2);

}  // namespace
}  // namespace dentsim
