// Long randomised runs of the simulated device (label `stress`; DENTSIM_STRESS=full for the long
// form): the device is passive. With zero-order hold the motors put exactly
// W_k = tau_k^T (q_k+1 - q_k) into the plant over tick k (true angles), so the mechanical energy
// obeys E_k+1 - E_k = W_k - D_k with D_k >= 0 the energy damping and friction dissipate; without
// them D_k = 0 up to the integrator's error.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "device/simulated_phantom.h"
#include "tests/device/test_plants.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

struct Balance {
  double worst_excess = -1e300;   // max_k (E_k+1 - E_k - W_k) [J]
  double total_dissipated = 0.0;  // sum_k (W_k - (E_k+1 - E_k)) [J]
  double total_work = 0.0;        // sum_k |W_k| [J]
};

Balance run(bool damping, bool friction, unsigned seed, long ticks) {
  SimulatedDeviceConfig c;
  c.damping_on = damping;
  c.friction_on = friction;
  c.frictionloss = VecX::Constant(6, 2e-3);
  c.saturate = false;
  c.tau_fault = VecX::Constant(6, 10.0);
  c.max_joint_step = 10.0;
  c.jitter.kind = TickJitterKind::kUniform;
  c.jitter.half_width = 3e-4;
  c.jitter.seed = seed;
  SimulatedPhantom dev(testing::arm_plant(), c, testing::arm_q0());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VecX scale(6);
  scale << 0.05, 0.05, 0.03, 0.002, 0.002, 0.001;
  VecX tau(6);
  Balance b;
  double E = dev.energy();
  for (long k = 0; k < ticks; ++k) {
    if (k % 50 == 0) {
      for (int j = 0; j < 6; ++j) tau[j] = scale[j] * u(rng);
    }
    const VecX q0 = dev.true_q();
    dev.write(tau);
    dev.advance();
    const double W = tau.dot(dev.true_q() - q0);
    const double E1 = dev.energy();
    b.worst_excess = std::max(b.worst_excess, E1 - E - W);
    b.total_dissipated += W - (E1 - E);
    b.total_work += std::abs(W);
    E = E1;
  }
  EXPECT_EQ(dev.faults(), kFaultNone);
  return b;
}

TEST(SimulatedPhantomStress, DeviceIsPassiveUnderRandomTorques) {
  const long ticks = testing::stress_count(3000, 60000);
  for (unsigned seed : {1u, 2u, 3u}) {
    // Viscous damping: every tick dissipates (dE <= W up to the integrator's error).
    const Balance d = run(true, false, seed, ticks);
    std::printf("seed %u, damping: max(dE - W) = %.3e J, dissipated %.4e J of |W| %.4e J\n", seed,
                d.worst_excess, d.total_dissipated, d.total_work);
    EXPECT_LE(d.worst_excess, 1e-9);
    EXPECT_GT(d.total_dissipated, 0.01 * d.total_work);
    // + Coulomb friction (MuJoCo frictionloss, a soft constraint solved per step): dissipative
    // overall, but a tick can give back up to ~2e-7 J (short form) / 1.3e-6 J (long form,
    // measured) of the constraint's regularised response, so the per-tick bound is looser.
    const Balance f = run(true, true, seed, ticks);
    std::printf(
        "seed %u, damping+friction: max(dE - W) = %.3e J, dissipated %.4e J of |W| %.4e J\n", seed,
        f.worst_excess, f.total_dissipated, f.total_work);
    EXPECT_LE(f.worst_excess, 5e-6);
    EXPECT_GT(f.total_dissipated, d.total_dissipated * 0.5);
    // Lossless: the motors' work is the energy change up to RK4's error, which grows with the
    // speed the undamped arm spins up to (long form: 3e-5 of the work, measured).
    const Balance n = run(false, false, seed, ticks);
    std::printf("seed %u, lossless: max(dE - W) = %.3e J, sum(W - dE) = %.3e J of |W| %.4e J\n",
                seed, n.worst_excess, n.total_dissipated, n.total_work);
    EXPECT_LT(std::abs(n.total_dissipated), 1e-4 * n.total_work);
  }
}

}  // namespace
}  // namespace dentsim
