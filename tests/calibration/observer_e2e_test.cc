// End to end (issue #5, "the observer with the fitted model estimates the hand force as well as
// with the true model and much better than with the unfitted defaults"): a simulated (MuJoCo)
// Phantom built from a perturbed model (the truth) is excited and logged, the log is fitted, and
// the momentum observer (validation/observer_report.h) runs on the same simulated device with the
// true, the fitted and the default (unfitted) model. docs/calibration.md has the numbers and the
// CLI commands that reproduce them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "calibration/excitation.h"
#include "calibration/fit.h"
#include "device/phantom_device.h"
#include "device/simulated_phantom.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"
#include "tests/calibration/truth_model.h"
#include "validation/observer_report.h"

namespace dentsim {
namespace {

// The perturbed device of tests/calibration/truth_model.h.
PhantomParams truth_model() { return testing::calibration_truth_model(); }

const ObserverRun& find_run(const ObserverReport& r, const std::string& name) {
  for (const ObserverRun& run : r.runs) {
    if (run.model == name) return run;
  }
  throw std::runtime_error("no run " + name);
}

TEST(CalibrationObserverE2E, FittedModelEstimatesTheHandForceAsWellAsTheTrueModel) {
  const PhantomParams truth = truth_model(), defaults = default_phantom_params();
  // 1. Excitation on the simulated Phantom of the truth (what `dentsim excite --device` does).
  ExcitationParams ep;
  ep.seed = 2;
  const VecX home = phantom_home_q(truth);
  const Excitation exc(truth, Vec6(home), ep);
  SimulatedPhantom dev(phantom_plant(truth), phantom_device_config(truth), home);
  const CalibrationLog log = run_excitation(dev, truth, exc, 20.0);
  // 2. The fit (what `dentsim calibrate` does, with its defaults).
  FitOptions fo;
  fo.lowpass_hz = 10.0;
  fo.max_samples = 1500;
  // The driver's velocity lags the angle; the torque is held over the tick (calibrate's default
  // --velocity-lag auto).
  const VelocityEstimatorParams vp = phantom_device_config(truth).velocity;
  const double lag = driver_velocity_lag_ticks(vp.filter == VelocityFilter::kFirstOrderLowPass,
                                               vp.cutoff_hz, 1e-3);
  fo.position_shift_samples = lag;
  fo.torque_shift_samples = lag + 0.5;
  const FitResult fit = fit_calibration(log, defaults, fo);
  ASSERT_TRUE(fit.converged) << fit.report;
  // 3. The observer with each model on the same simulated device.
  const ObserverReportConfig c;
  const PhantomModel m_true(observer_true_params(truth, c)), m_fit(fit.fitted), m_def(defaults);
  const ObserverReport r =
      run_observer_models(truth, c, {{"true", &m_true}, {"fitted", &m_fit}, {"default", &m_def}});
  std::printf("%s", observer_report_table(r).c_str());
  const ObserverRun &t = find_run(r, "true"), &f = find_run(r, "fitted"),
                    &d = find_run(r, "default");
  const auto max_abs = [](const VecX& v) { return v.cwiseAbs().maxCoeff(); };
  // Margin for "as well as the true model": 0.5 mN m per joint. Reason: the fit leaves the
  // gravity torque ~0.2 % off (g ~ 0.1 N m on q2: 0.2 mN m), and the encoder quantum in g(q) and
  // the hold's limit cycle move the steady estimate by up to 0.2 mN m (observer_report_test).
  // Measured on q2 (docs/calibration.md): steady 2.19 vs 2.23 mN m, moving bias +0.07 vs
  // -0.17 mN m, bias along the motion -0.75 vs -0.36 mN m.
  const double margin = 5e-4;
  // Along the motion the fitted friction law differs from the true model's by design: the fit
  // chooses v_s per joint (0.045 rad/s on q2, the true model's 0.01) as the law MuJoCo's
  // frictionloss shows under the excitation's sensing, and the true model is not the plant's law
  // either. Measured on q2: -1.14 mN m fitted, -0.36 true, +1.09 default; 1 mN m allowed (11 % of
  // q2's Coulomb friction).
  const double along_margin = 1e-3;
  for (int j = 0; j < 6; ++j) {
    EXPECT_LE(std::abs(f.steady_error[j]), std::abs(t.steady_error[j]) + margin) << "q" << j + 1;
    EXPECT_LE(std::abs(f.moving_bias[j]), std::abs(t.moving_bias[j]) + margin) << "q" << j + 1;
    EXPECT_NEAR(f.moving_bias_along_motion[j], t.moving_bias_along_motion[j], along_margin)
        << "q" << j + 1;
  }
  // In motion the RMS error is dominated by the velocity estimate's quantisation noise (L M qd
  // in f_hat, ~20 mN m on q2 whatever the model): the fitted model's may exceed the true model's
  // by what a few % of inertia error add to it (10 %) plus the same 0.5 mN m (measured on q5,
  // the gimbal pitch, whose Coulomb friction the fit gets 26 % low: 1.47 vs 1.11 mN m).
  for (int j = 0; j < 6; ++j) {
    EXPECT_LE(f.moving_rms_beyond_lag[j], 1.1 * t.moving_rms_beyond_lag[j] + margin)
        << "q" << j + 1;
  }
  // "Much better than the unfitted defaults": the defaults' gravity is ~28 % off (masses
  // +-20 %), their damping 3x and Coulomb 1.5x too small. Their steady error and moving bias
  // are >= 5x the fitted model's (measured 26.5 vs 2.2 mN m and 23.5 vs 0.40 mN m), their bias
  // along the motion >= 1.5x further from the true model's (largest difference over the joints:
  // measured 3.3 mN m on q3 vs 0.78 mN m on q2, the fitted v_s above), and
  // their RMS error in motion >= 1.3x the true model's on q2 (measured 32.1 vs 21.6 mN m).
  EXPECT_GT(max_abs(d.steady_error), 5.0 * max_abs(f.steady_error));
  EXPECT_GT(max_abs(d.moving_bias), 5.0 * max_abs(f.moving_bias));
  EXPECT_GT(max_abs(d.moving_bias_along_motion - t.moving_bias_along_motion),
            1.5 * max_abs(f.moving_bias_along_motion - t.moving_bias_along_motion));
  EXPECT_GT(d.moving_rms_beyond_lag[1], 1.3 * t.moving_rms_beyond_lag[1]);
}

}  // namespace
}  // namespace dentsim
