// Excitation (calibration/excitation.h): the trajectory's analytic derivatives, its limits, and
// a run under PD tracking on the simulated (MuJoCo) Phantom.
#include "calibration/excitation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <string>

#include "device/phantom_device.h"
#include "device/simulated_phantom.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

TEST(Excitation, DerivativesMatchCentralDifferences) {
  const PhantomParams p = default_phantom_params();
  ExcitationParams ep;
  ep.seed = 3;
  std::printf("seed 3\n");
  const Excitation exc(p, phantom_home_q(p), ep);
  double err_v = 0.0, err_a = 0.0;
  const double h = 1e-5;
  for (double t : {0.1, 0.5, 0.99, 1.3, 2.7, 4.4, 7.9}) {
    Vec6 qm, qdm, qddm, q, qd, qdd, qp, qdp, qddp;
    exc.eval(t - h, &qm, &qdm, &qddm);
    exc.eval(t, &q, &qd, &qdd);
    exc.eval(t + h, &qp, &qdp, &qddp);
    err_v = std::max(err_v, ((qp - qm) / (2 * h) - qd).cwiseAbs().maxCoeff());
    err_a = std::max(err_a, ((qdp - qdm) / (2 * h) - qdd).cwiseAbs().maxCoeff());
  }
  std::printf("max |FD - analytic|: qd %.3g rad/s, qdd %.3g rad/s^2\n", err_v, err_a);
  EXPECT_LT(err_v, 1e-6);
  EXPECT_LT(err_a, 1e-5);
  // Starts at rest at the home pose.
  Vec6 q, qd, qdd;
  exc.eval(0.0, &q, &qd, &qdd);
  EXPECT_LT((q - exc.q0()).norm(), 1e-15);
  EXPECT_LT(qd.norm(), 1e-15);
}

// The joint range, velocity and model torque over 30 s at 1 kHz (several periods of the series).
void expect_within_limits(const PhantomParams& p, const Excitation& exc, const char* what) {
  const PhantomModelD model(p);
  const ExcitationParams& ep = exc.params();
  Vec6 range_lo = Vec6::Constant(1e9), range_hi = Vec6::Constant(-1e9);
  double torque_ratio = 0.0, vel_ratio = 0.0;
  for (int k = 0; k <= 30000; ++k) {
    Vec6 q, qd, qdd;
    exc.eval(1e-3 * k, &q, &qd, &qdd);
    range_lo = range_lo.cwiseMin(q);
    range_hi = range_hi.cwiseMax(q);
    const Vec6 tau = model.M(q) * qdd + model.bias(q, qd) + model.g(q) + model.friction(qd);
    torque_ratio =
        std::max(torque_ratio, tau.cwiseQuotient(p.torque_limit_n_m).cwiseAbs().maxCoeff());
    vel_ratio = std::max(vel_ratio, qd.cwiseQuotient(ep.qd_max_rad_s).cwiseAbs().maxCoeff());
  }
  std::printf("%s: max |tau|/tau_max %.3f, max |qd|/qd_max %.3f, min range %.3f rad\n", what,
              torque_ratio, vel_ratio, (range_hi - range_lo).minCoeff());
  for (int j = 0; j < 6; ++j) {
    EXPECT_GE(range_lo(j), p.q_min_rad(j) + ep.limit_margin_rad - 1e-9) << what << " " << j;
    EXPECT_LE(range_hi(j), p.q_max_rad(j) - ep.limit_margin_rad + 1e-9) << what << " " << j;
    EXPECT_GT(range_hi(j) - range_lo(j), 0.05) << what << ": joint " << j + 1 << " barely moves";
  }
  // The torque scaling is checked on a 2 ms grid over the ramp and one period; the 1 ms grid
  // may see a little more.
  EXPECT_LE(torque_ratio, ep.torque_fraction * 1.02) << what;
  EXPECT_LE(vel_ratio, 1.0 + 1e-9) << what;
}

TEST(Excitation, StaysWithinJointVelocityAndTorqueLimits) {
  const PhantomParams p = default_phantom_params();
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    ExcitationParams ep;
    ep.seed = seed;
    const Excitation exc(p, phantom_home_q(p), ep);
    expect_within_limits(p, exc, ("seed " + std::to_string(seed)).c_str());
  }
}

// The design (issue #17): a lower condition number at the same rank, within the same limits,
// reproducible from the seed; the condition number is the fit's (column-normalised regressor).
TEST(Excitation, DesignLowersTheConditionNumberWithinTheLimits) {
  const PhantomParams p = default_phantom_params();
  for (std::uint64_t seed : {1u}) {
    ExcitationParams ep;
    ep.seed = seed;
    const ExcitationDesign d = design_excitation(p, phantom_home_q(p), ep, 12);
    std::printf("seed %llu: condition %.1f -> %.1f (rank %d, %d of %d steps kept)\n",
                static_cast<unsigned long long>(seed), d.condition_seeded, d.condition_designed,
                d.rank, d.accepted, d.iterations);
    EXPECT_EQ(d.iterations, 12);
    EXPECT_GT(d.accepted, 0);
    EXPECT_LT(d.condition_designed, d.condition_seeded);
    // The seeded series' rank is the fit's structural count of identifiable directions (31 of
    // the 50 parameters' combinations on the Phantom: fit_test), and the design keeps it.
    EXPECT_EQ(excitation_condition(p, d.excitation, 100, 0).rank, d.rank);
    EXPECT_NEAR(excitation_condition(p, d.excitation, 100, d.rank).condition_number,
                d.condition_designed, 1e-9 * d.condition_designed);
    expect_within_limits(p, d.excitation, ("designed, seed " + std::to_string(seed)).c_str());
    // Reproducible.
    const ExcitationDesign again = design_excitation(p, phantom_home_q(p), ep, 12);
    EXPECT_EQ(again.excitation.a(), d.excitation.a());
    EXPECT_EQ(again.condition_designed, d.condition_designed);
  }
}

TEST(Excitation, PdTrackingOnTheSimulatedPhantomLogsAppliedTorque) {
  const PhantomParams p = default_phantom_params();
  ExcitationParams ep;
  ep.seed = 1;
  const VecX home = phantom_home_q(p);
  const Excitation exc(p, home, ep);
  SimulatedPhantom dev(phantom_plant(p), phantom_device_config(p), home);
  const CalibrationLog log = run_excitation(dev, p, exc, 4.0);
  ASSERT_EQ(log.size(), 4001);
  Vec6 err_j = Vec6::Zero();
  double err = 0.0, sat = 0.0;
  for (int k = 0; k < log.size(); ++k) {
    Vec6 q, qd, qdd;
    exc.eval(log.t[k], &q, &qd, &qdd);
    err_j = err_j.cwiseMax((log.q[k] - q).cwiseAbs());
    err = err_j.maxCoeff();
    sat = std::max(sat, log.tau[k].cwiseQuotient(p.torque_limit_n_m).cwiseAbs().maxCoeff());
    if (k > 0) {
      ASSERT_NEAR(log.t[k] - log.t[k - 1], 1e-3, 1e-12);
    }
  }
  std::printf(
      "max tracking error %.4f rad (per joint %.4f %.4f %.4f %.4f %.4f %.4f), "
      "max |tau|/tau_max %.3f\n",
      err, err_j(0), err_j(1), err_j(2), err_j(3), err_j(4), err_j(5), sat);
  EXPECT_LT(err, 0.05);  // the fit does not need tracking, but the run must stay near the plan
  EXPECT_LE(sat, 1.0 + 1e-12);
  // The log round-trips through the file format and passes its checks.
  const CalibrationLog back = parse_calibration_log(calibration_log_to_text(log), "mem");
  EXPECT_EQ(back.size(), log.size());
}


// A busy machine, deterministically (no wall clock): every `every`-th step of the loop is late by
// `late` device ticks, over which the device keeps running with the torque held (as a real arm
// does while its loop is not scheduled). The loop sees a device-clock jump of late + 1 ticks.
class LateTickDevice : public Device {
 public:
  LateTickDevice(Device& inner, int every, int late) : inner_(inner), every_(every), late_(late) {}
  const DeviceCapabilities& capabilities() const override { return inner_.capabilities(); }
  const DeviceLimits& limits() const override { return inner_.limits(); }
  void read(DeviceSample& out) const override { inner_.read(out); }
  void write(const VecX& tau) override {
    inner_.write(tau);
    max_written_ratio_ = std::max(
        max_written_ratio_, tau.cwiseAbs().cwiseQuotient(inner_.limits().tau_max).maxCoeff());
  }
  void advance() override {
    inner_.advance();
    if (every_ > 0 && ++steps_ % every_ == 0) {
      for (int i = 0; i < late_; ++i) inner_.advance();
    }
  }
  const VecX& applied_torque() const override { return inner_.applied_torque(); }
  std::uint32_t faults() const override { return inner_.faults(); }
  void clear_faults() override { inner_.clear_faults(); }
  double max_written_ratio() const { return max_written_ratio_; }

 private:
  Device& inner_;
  int every_, late_;
  long steps_ = 0;
  double max_written_ratio_ = 0.0;
};

PhantomParams scaled_masses(double f, const std::string& name) {
  PhantomParams p = default_phantom_params();
  p.name = name;
  for (PhantomBody* b : {&p.base, &p.upper_arm, &p.forearm, &p.crank, &p.parallel_link,
                         &p.gimbal_yaw, &p.gimbal_pitch, &p.gimbal_roll}) {
    b->mass_kg *= f;
    b->inertia_kg_m2 *= f;
  }
  p.armature_kg_m2 *= f;
  return p;
}

// Issue #33: a new device's model is not known. The guarded run (hold with the integral action
// ramped in, approach, settle, excitation with torque clamp and velocity guard, clean stop) on
// simulated devices the prior (the default model) gets wrong — gravity off, every mass and
// inertia +30 % or -30 %, masses mixed with x3 damping and x2 Coulomb friction on a loop that is
// late by 40 ticks every 37 steps — completes, never commands beyond tau_max (the fault threshold
// is 4 tau_max) and excites the arm. With gravity off, the hold identifies the prior's gravity
// error at home: the integral action there is -g_prior(home) up to the joints' Coulomb friction.
TEST(Excitation, GuardedRunStaysWithinTheLimitsOnDevicesThePriorGetsWrong) {
  const PhantomParams prior = default_phantom_params();
  const PhantomModelD prior_model(prior);
  ExcitationParams ep;
  ep.seed = 1;
  const Excitation exc(prior, phantom_home_q(prior), ep);
  PhantomParams no_gravity = default_phantom_params();
  no_gravity.name = "gravity off";
  no_gravity.gravity_on = false;
  PhantomParams mixed = default_phantom_params();
  mixed.name = "mixed";
  mixed.upper_arm.mass_kg *= 1.3;
  mixed.forearm.mass_kg *= 0.7;
  mixed.crank.mass_kg *= 1.3;
  mixed.gimbal_roll.mass_kg *= 0.7;
  mixed.damping_n_m_s_per_rad *= 3.0;
  mixed.coulomb_n_m *= 2.0;
  struct Case {
    PhantomParams device;
    int late_every, late_ticks;
  };
  const Case cases[] = {{no_gravity, 0, 0},
                        {scaled_masses(1.3, "masses +30 %"), 0, 0},
                        {scaled_masses(0.7, "masses -30 %"), 0, 0},
                        {mixed, 37, 40}};
  const double duration = 4.0;
  for (const Case& c : cases) {
    SimulatedPhantom sim(phantom_plant(c.device), phantom_device_config(c.device),
                         phantom_home_q(c.device));
    LateTickDevice dev(sim, c.late_every, c.late_ticks);
    const ExcitationOutcome r = run_guarded_excitation(dev, prior, exc, duration);
    const CalibrationLog& log = r.log;
    Vec6 lo = Vec6::Constant(1e9), hi = Vec6::Constant(-1e9);
    double applied = 0.0;
    for (int k = 0; k < log.size(); ++k) {
      lo = lo.cwiseMin(log.q[k]);
      hi = hi.cwiseMax(log.q[k]);
      applied = std::max(applied,
                         log.tau[k].cwiseAbs().cwiseQuotient(prior.torque_limit_n_m).maxCoeff());
    }
    const Vec6 range = hi - lo;
    std::printf(
        "%s: complete %d (%s), %d samples over %.3f s, max |tau_cmd|/tau_max %.3f (written %.3f),"
        " applied %.3f, clamped %ld / %ld ticks, late %ld, slowed %ld (min scale %.3f), max speed "
        "%.3f rad/s, q range %.3f %.3f %.3f %.3f %.3f %.3f, gravity offset %.4f %.4f %.4f\n",
        c.device.name.c_str(), r.complete, r.stop_reason.c_str(), log.size(),
        log.size() ? log.t.back() : 0.0, r.max_command_ratio, dev.max_written_ratio(), applied,
        r.clamped_ticks, r.ticks, r.late_ticks, r.guard_ticks, r.min_time_scale,
        r.max_speed_rad_s, range(0), range(1), range(2), range(3), range(4), range(5),
        r.gravity_offset(0), r.gravity_offset(1), r.gravity_offset(2));
    ASSERT_TRUE(r.complete) << c.device.name << ": " << r.stop_reason;
    EXPECT_EQ(r.fault, kFaultNone) << c.device.name;
    EXPECT_TRUE(log.incomplete.empty()) << c.device.name;
    EXPECT_LE(dev.max_written_ratio(), 1.0 + 1e-12) << c.device.name;
    EXPECT_LE(r.max_command_ratio, 1.0 + 1e-12) << c.device.name;
    EXPECT_LE(applied, 1.0 + 1e-12) << c.device.name;
    EXPECT_GE(log.t.back(), duration - 0.05) << c.device.name;
    if (c.late_every > 0) {
      EXPECT_GT(r.late_ticks, 50) << c.device.name;
    }
    // Excited: every joint moves at least 0.1 rad over the log, inside its range.
    for (int j = 0; j < 6; ++j) {
      EXPECT_GT(range(j), 0.1) << c.device.name << " joint " << j + 1;
      EXPECT_GE(lo(j), prior.q_min_rad(j) - 0.05) << c.device.name << " joint " << j + 1;
      EXPECT_LE(hi(j), prior.q_max_rad(j) + 0.05) << c.device.name << " joint " << j + 1;
    }
    if (!c.device.gravity_on) {
      const Vec6 g = prior_model.g(exc.q0());
      for (int j = 1; j < 3; ++j) {
        EXPECT_NEAR(r.gravity_offset(j), -g(j), c.device.coulomb_n_m(j) + 0.05 * std::abs(g(j)))
            << "joint " << j + 1;
      }
    }
  }
}

// A stop request (SIGINT in `dentsim excite`) during the excitation ends it cleanly: the log up to
// the request, marked incomplete, the excitation faded out and the torque ramped down to zero.
TEST(Excitation, GuardedRunStopsCleanlyOnRequestWithTheLogSoFar) {
  const PhantomParams p = default_phantom_params();
  ExcitationParams ep;
  const Excitation exc(p, phantom_home_q(p), ep);
  SimulatedPhantom sim(phantom_plant(p), phantom_device_config(p), phantom_home_q(p));
  // The request arrives 1.5 s into the excitation (hold 2 s, approach 0.5 s, settle 1 s).
  class RequestAt : public LateTickDevice {
   public:
    RequestAt(Device& inner, std::atomic<bool>* flag) : LateTickDevice(inner, 0, 0), flag_(flag) {}
    void read(DeviceSample& out) const override {
      LateTickDevice::read(out);
      if (out.t >= 5.0) flag_->store(true);
    }

   private:
    std::atomic<bool>* flag_;
  };
  std::atomic<bool> stop{false};
  RequestAt dev(sim, &stop);
  const ExcitationOutcome r = run_guarded_excitation(dev, p, exc, 10.0, {}, {}, &stop);
  EXPECT_FALSE(r.complete);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.fault, kFaultNone);
  EXPECT_EQ(r.log.incomplete, r.stop_reason);
  EXPECT_EQ(r.stop_reason.rfind("interrupted at t = ", 0), 0u) << r.stop_reason;
  ASSERT_GT(r.log.size(), 1000);
  EXPECT_LT(r.log.t.back(), 2.0);
  EXPECT_NEAR(r.log.t.back(), r.stop_t, 2e-3);
  EXPECT_EQ(sim.applied_torque().norm(), 0.0);  // ramped down to zero at the end
}

}  // namespace
}  // namespace dentsim
