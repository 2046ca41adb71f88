// Calibration over seeded held-out devices (calibration/seeds.h, `dentsim calibrate-seeds`):
// the seeded perturbation, the bar's bookkeeping, the truth-model error, and issue #17's property
// test over seeds in its short form (CI).
#include "calibration/seeds.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "calibration/log.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"
#include "tests/support/cli.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

// The perturbed fields of `p`, in perturb_device's drawing order.
std::vector<double> perturbed_fields(const PhantomParams& p) {
  std::vector<double> v;
  for (const PhantomBody* b : {&p.base, &p.upper_arm, &p.forearm, &p.crank, &p.parallel_link,
                               &p.gimbal_yaw, &p.gimbal_pitch, &p.gimbal_roll}) {
    v.push_back(b->mass_kg);
    v.push_back(b->inertia_kg_m2(0));
  }
  for (const Vec6* x : {&p.armature_kg_m2, &p.damping_n_m_s_per_rad, &p.coulomb_n_m})
    for (int j = 0; j < 6; ++j) v.push_back((*x)(j));
  return v;
}

TEST(CalibrationSeeds, PerturbationIsSeededAndScalesEachFieldByItsFactor) {
  const PhantomParams base = default_phantom_params();
  const PerturbedDevice a = perturb_device(base, 7), b = perturb_device(base, 7),
                        c = perturb_device(base, 8);
  // Same seed: the identical model; another seed: every factor differs.
  EXPECT_EQ(a.params, b.params);
  EXPECT_EQ(a.factors, b.factors);
  EXPECT_NE(a.params, c.params);
  ASSERT_EQ(a.factors.size(), 34u);
  ASSERT_EQ(a.factor_names.size(), 34u);
  EXPECT_EQ(a.factor_names.front(), "base.mass_kg");
  EXPECT_EQ(a.factor_names[15], "gimbal_roll.inertia_kg_m2");
  EXPECT_EQ(a.factor_names.back(), "coulomb_n_m.6");
  for (std::size_t i = 0; i < a.factors.size(); ++i) EXPECT_NE(a.factors[i], c.factors[i]) << i;

  // Each perturbed field is its base value times its factor (one factor for the three principal
  // moments of a body); everything else is the base's.
  const std::vector<double> f0 = perturbed_fields(base), f1 = perturbed_fields(a.params);
  ASSERT_EQ(f1.size(), a.factors.size());
  for (std::size_t i = 0; i < f1.size(); ++i) {
    EXPECT_DOUBLE_EQ(f1[i], f0[i] * a.factors[i]) << a.factor_names[i];
  }
  EXPECT_DOUBLE_EQ(a.params.gimbal_roll.inertia_kg_m2(2),
                   base.gimbal_roll.inertia_kg_m2(2) * a.factors[15]);
  PhantomParams restored = a.params;
  for (PhantomBody PhantomParams::*m :
       {&PhantomParams::base, &PhantomParams::upper_arm, &PhantomParams::forearm,
        &PhantomParams::crank, &PhantomParams::parallel_link, &PhantomParams::gimbal_yaw,
        &PhantomParams::gimbal_pitch, &PhantomParams::gimbal_roll}) {
    (restored.*m).mass_kg = (base.*m).mass_kg;
    (restored.*m).inertia_kg_m2 = (base.*m).inertia_kg_m2;
  }
  restored.armature_kg_m2 = base.armature_kg_m2;
  restored.damping_n_m_s_per_rad = base.damping_n_m_s_per_rad;
  restored.coulomb_n_m = base.coulomb_n_m;
  EXPECT_EQ(restored.name, "perturbed default Phantom, seed 7");
  restored.name = base.name;
  EXPECT_EQ(restored, base);

  // The documented generator: the first factor is 0.75 + 0.6 u, u the top 53 bits of the first
  // draw of std::mt19937_64(seed) over 2^53 (not Python's random.uniform).
  std::mt19937_64 rng(7);
  EXPECT_EQ(a.factors[0], 0.75 + 0.6 * (static_cast<double>(rng() >> 11) * 0x1.0p-53));
}

TEST(CalibrationSeeds, FactorsCoverTheRangeUniformly) {
  // 200 seeds x 34 factors: all in [0.75, 1.35], both ends approached, mean 1.05 (the standard
  // error of the mean of 6800 uniform draws is 0.6 / sqrt(12 * 6800) = 0.0021: 5 of them).
  double lo = 2.0, hi = 0.0, sum = 0.0;
  int n = 0;
  for (std::uint64_t s = 1; s <= 200; ++s) {
    for (double f : perturb_device(default_phantom_params(), s).factors) {
      ASSERT_GE(f, kSeedFactorMin);
      ASSERT_LE(f, kSeedFactorMax);
      lo = std::min(lo, f), hi = std::max(hi, f), sum += f, ++n;
    }
  }
  EXPECT_LT(lo, 0.76);
  EXPECT_GT(hi, 1.34);
  EXPECT_NEAR(sum / n, 1.05, 5 * 0.0021);
}

TEST(CalibrationSeeds, TruthModelErrorOfAUniformlyScaledModel) {
  // M(q) is linear and homogeneous in the masses, inertias and armatures (at fixed geometry) and
  // g(q) in the masses: scaling all of them by 1.1 makes both exactly 10 % off at every pose.
  const PhantomParams t = default_phantom_params();
  EXPECT_EQ(truth_model_error(t, t), ModelError{});
  PhantomParams m = t;
  for (PhantomBody* b : {&m.base, &m.upper_arm, &m.forearm, &m.crank, &m.parallel_link,
                         &m.gimbal_yaw, &m.gimbal_pitch, &m.gimbal_roll}) {
    b->mass_kg *= 1.1;
    b->inertia_kg_m2 *= 1.1;
  }
  m.armature_kg_m2 *= 1.1;
  const ModelError e = truth_model_error(t, m);
  EXPECT_NEAR(e.mass_matrix, 0.1, 1e-12);
  EXPECT_NEAR(e.arm_mass_matrix, 0.1, 1e-12);
  EXPECT_NEAR(e.gravity, 0.1, 1e-12);
}

SeedParameter param(const std::string& name, bool identifiable, double rel, double eos) {
  SeedParameter p;
  p.name = name;
  p.identifiable = identifiable;
  p.truth = 2.0;
  p.value = 2.0 * (1.0 + rel);
  p.std = eos > 0.0 ? 2.0 * rel / eos : 0.0;
  p.rel_error = rel;
  p.error_over_std = eos;
  return p;
}

TEST(CalibrationSeeds, SummaryCountsWhatIsOutsideBothBarsAndRoundTripsThroughJson) {
  SeedResult a;
  a.seed = 3;
  a.converged = true;
  a.fitted.mass_matrix = 0.030;
  a.model_mismatch = true;
  a.model_mismatch_reasons = {"joint 2: slow residual 3.3x fast"};
  a.params = {param("upper_arm.mass_kg", true, 0.05, 10.0),        // at 5 %: within
              param("damping_n_m_s_per_rad.1", true, 0.06, 3.0),   // at 3 std: within
              param("damping_n_m_s_per_rad.2", true, 0.06, 3.01),  // outside both
              param("coulomb_n_m.5", true, 0.4,
                    std::numeric_limits<double>::infinity()),  // outside, std 0, gimbal
              param("forearm.mass_kg", false, 0.0, 0.0)};      // not checked
  SeedResult b = a;
  b.seed = 4;
  b.converged = false;
  b.model_mismatch = false;
  b.fitted.mass_matrix = 0.010;
  b.params = {param("coulomb_n_m.1", true, 0.5, 4.0)};
  SeedResult c = b;
  c.seed = 5;
  c.fitted.mass_matrix = 0.020;
  c.params = {};
  SeedResult d = c;
  d.seed = 6;
  d.fitted.mass_matrix = 0.021;

  ASSERT_EQ(a.checked(), 4);
  ASSERT_EQ(a.outside().size(), 2u);
  EXPECT_EQ(a.outside()[0].name, "damping_n_m_s_per_rad.2");
  EXPECT_TRUE(is_gimbal_coulomb(a.outside()[1].name));
  EXPECT_FALSE(is_gimbal_coulomb("coulomb_n_m.3"));
  const SeedSummary s = summarize({a, b, c, d});
  EXPECT_EQ(s.fits, 4);
  EXPECT_EQ(s.converged, 1);
  EXPECT_EQ(s.checked, 5);
  EXPECT_EQ(s.outside, 3);
  EXPECT_EQ(s.outside_gimbal_coulomb, 1);
  EXPECT_DOUBLE_EQ(s.mass_matrix_median, 0.0205);  // mean of the middle two of 4
  EXPECT_EQ(s.mass_matrix_max, 0.030);
  EXPECT_EQ(s.mass_matrix_within_bar, 2);  // 0.010 and 0.020 (the bar is inclusive)
  EXPECT_EQ(s.model_mismatch_flagged, 1);
  EXPECT_DOUBLE_EQ(summarize({a, b, c}).mass_matrix_median, 0.020);
  // error / std over the 5 checks (10, 3, 3.01, inf, 4): RMS over the finite four, the infinite
  // one beyond every bound, 3 itself not beyond 3.
  EXPECT_DOUBLE_EQ(s.error_over_std_rms, std::sqrt((100.0 + 9.0 + 3.01 * 3.01 + 16.0) / 4.0));
  EXPECT_EQ(s.beyond_1_std, 5);
  EXPECT_EQ(s.beyond_2_std, 5);
  EXPECT_EQ(s.beyond_3_std, 4);

  // Through JSON text (as the MPI gather carries it): bit-identical, infinity as null.
  const nlohmann::json j = nlohmann::json::parse(seed_result_to_json(a).dump());
  EXPECT_TRUE(j.at("parameters")[3].at("error_over_std").is_null());
  EXPECT_EQ(j.at("outside_bar"), nlohmann::json({"damping_n_m_s_per_rad.2", "coulomb_n_m.5"}));
  EXPECT_EQ(seed_result_from_json(j), a);
  const nlohmann::json js = seed_summary_to_json(s);
  EXPECT_EQ(js.at("outside_bar"), 3);
  EXPECT_EQ(js.at("mass_matrix_within_bar"), 2);
  EXPECT_EQ(js.at("beyond_3_std"), 4);
  EXPECT_EQ(js.at("error_over_std_rms").get<double>(), s.error_over_std_rms);
}

// ---- issue #17's property test over seeds, short form (CI) ----------------------------------
//
// Issue #17's bar on the default simulated plant (MuJoCo's frictionloss, quantised encoders, the
// driver's velocity estimate) and seeded held-out perturbations: every identifiable parameter
// within 5 % or within 3 reported std, and the fitted M(q) within 2 %. Short form: seed 1 (CI;
// seeds 1..3 with DENTSIM_STRESS=full), the excitation designed as `dentsim excite` designs it
// (40 iterations) but 8 s long, 1500 samples, both model-mismatch terms on: about 17 s of CPU per
// seed in Release. The long form is `dentsim calibrate-seeds --count 20` (docs/calibration.md has
// its table: 0 of 230 outside). Measured on seeds 1..3: 33 parameters checked, none outside;
// M(q) 0.27-0.33 %. The excitation as drawn
// (no design iterations) is a weaker experiment: on it seed 2's coulomb_n_m.6 is 7.9 % off at
// 3.96 reported std (docs/calibration.md).

constexpr std::uint64_t kFirstSeed = 1;
// One seed in CI, three with DENTSIM_STRESS=full (docs/results/ci_time.md).
const int kSeeds = static_cast<int>(testing::stress_count(1, 3));

SeedRunOptions short_options() {
  SeedRunOptions o;
  o.duration_s = 8.0;
  o.max_samples = 1500;
  return o;
}

// The short form's fits, run once for the suite and printed (every identifiable parameter's
// error), so that a failure shows what moved.
const std::vector<SeedResult>& short_results() {
  static const std::vector<SeedResult> results = [] {
    std::vector<SeedResult> r;
    for (int i = 0; i < kSeeds; ++i) {
      r.push_back(run_seed(default_phantom_params(), kFirstSeed + i, short_options()).result);
      const SeedResult& s = r.back();
      std::printf(
          "seed %llu: converged %d, model_mismatch %d, %d identifiable, M(q) error fitted "
          "%.3f %% (prior %.3f %%), gimbal block %.3f %% (prior %.3f %%), g(q) %.3f %%\n",
          static_cast<unsigned long long>(s.seed), s.converged, s.model_mismatch, s.checked(),
          100 * s.fitted.mass_matrix, 100 * s.prior.mass_matrix, 100 * s.fitted.gimbal_mass_matrix,
          100 * s.prior.gimbal_mass_matrix, 100 * s.fitted.gravity);
      for (const SeedParameter& p : s.params) {
        if (!p.identifiable) continue;
        std::printf("  %-26s %+8.3f %% %7.2f std (statistical %.3g, slow rows %.3g, law %.3g)%s\n",
                    p.name.c_str(), 100 * (p.value / p.truth - 1.0), p.error_over_std,
                    p.std_statistical, p.std_model, p.std_law,
                    within_bar(p) ? "" : "  outside the bar");
      }
    }
    return r;
  }();
  return results;
}

// Issue #17's bar and the law term's share of the std, in one test (ctest runs each test in its
// own process: the fits run once).
TEST(CalibrationSeedsProperty, EveryIdentifiableWithin5PercentOr3StdAndMassMatrixWithin2Percent) {
  for (const SeedResult& r : short_results()) {
    EXPECT_TRUE(r.converged) << "seed " << r.seed;
    for (const SeedParameter& p : r.outside()) {
      ADD_FAILURE() << "seed " << r.seed << ": " << p.name << " " << 100 * p.rel_error
                    << " % off at " << p.error_over_std << " reported std";
    }
    // Not met by checking nothing: the arm's damping and Coulomb friction and the gimbal's
    // Coulomb friction at least (measured 11 identifiable per seed).
    int gimbal_coulomb = 0;
    for (const SeedParameter& p : r.params)
      gimbal_coulomb += p.identifiable && is_gimbal_coulomb(p.name);
    EXPECT_GE(r.checked(), 8) << "seed " << r.seed;
    EXPECT_GE(gimbal_coulomb, 1) << "seed " << r.seed;
    // M(q): issue #17's 2 % (measured on seeds 1..3: 0.27-0.33 %), and well below the prior's
    // error (4.2-6.7 %).
    EXPECT_LE(r.fitted.mass_matrix, kMassMatrixBar) << "seed " << r.seed;
    EXPECT_LT(r.fitted.mass_matrix, 0.1 * r.prior.mass_matrix) << "seed " << r.seed;
    // The gimbal's block, which the whole matrix cannot see: not degenerate (the fit used to put
    // the gimbal inertias at their lower bound, 1e-3 of the prior). Worst measured 8.3 %; 8 s
    // of excitation pins it loosely: bound 30 %.
    EXPECT_LE(r.fitted.gimbal_mass_matrix, 0.3) << "seed " << r.seed;
    // MuJoCo's frictionloss is not the model's tanh law: the fit says so on every seed.
    EXPECT_TRUE(r.model_mismatch) << "seed " << r.seed;
    // The reported std is the three terms in quadrature; the law term is large where the smooth
    // sign matters (some gimbal Coulomb friction: measured 3.1-5.8 statistical std per seed) and
    // small where it does not (the arm's Coulomb friction: measured below 1).
    double gimbal_max = 0.0;
    for (const SeedParameter& p : r.params) {
      EXPECT_NEAR(
          p.std * p.std,
          p.std_statistical * p.std_statistical + p.std_model * p.std_model + p.std_law * p.std_law,
          1e-9 * p.std * p.std + 1e-300)
          << p.name;
      if (!p.identifiable || p.name.rfind("coulomb_n_m.", 0) != 0) continue;
      if (is_gimbal_coulomb(p.name)) {
        gimbal_max = std::max(gimbal_max, p.std_law / p.std_statistical);
      } else {
        EXPECT_LT(p.std_law, 2.0 * p.std_statistical) << "seed " << r.seed << ": " << p.name;
      }
    }
    EXPECT_GT(gimbal_max, 1.5) << "seed " << r.seed;
  }
}

// ---- the command --------------------------------------------------------------------------

using dentsim::testing::CliRun;
using dentsim::testing::fresh_temp_dir;
using dentsim::testing::read_json_file;
using dentsim::testing::run_dentsim;

std::string file_text(const std::filesystem::path& p) { return read_file(p.string()); }

TEST(CalibrateSeedsCli, OneSeedEqualsTheLibraryAndExciteThenCalibrate) {
  // A tiny run (3 s, 2 design iterations, 500 samples): the command's JSON entry is the
  // library's, number for number, and so are `excite --device truth` + `calibrate --truth` on
  // the truth file the command kept.
  namespace fs = std::filesystem;
  const fs::path d = fresh_temp_dir("dentsim_calibrate_seeds_cli");
  SeedRunOptions o;
  o.duration_s = 3.0;
  o.design_iterations = 2;
  o.max_samples = 500;
  const SeedRun lib = run_seed(default_phantom_params(), 4, o);

  const CliRun cs = run_dentsim(
      "calibrate-seeds --first 4 --count 1 --duration 3 "
      "--design-iterations 2 --max-samples 500 --json " +
      (d / "seeds.json").string() + " --out " + (d / "out").string());
  ASSERT_EQ(cs.status, 0) << cs.output;
  const nlohmann::json j = read_json_file(d / "seeds.json");
  ASSERT_EQ(j.at("seeds").size(), 1u);
  EXPECT_EQ(j.at("seeds")[0], seed_result_to_json(lib.result));
  EXPECT_EQ(j.at("summary"), seed_summary_to_json(summarize({lib.result})));
  const fs::path s4 = d / "out" / "seed4";
  EXPECT_EQ(file_text(s4 / "truth.json"), phantom_params_to_text(lib.truth));
  EXPECT_EQ(file_text(s4 / "model.json"), phantom_params_to_text(lib.fitted));
  EXPECT_EQ(read_calibration_log((s4 / "log.csv").string()).tau, lib.log.tau);

  const CliRun ex =
      run_dentsim("excite --device " + (s4 / "truth.json").string() + " -o " +
                  (d / "log.csv").string() + " --duration 3 --seed 4 --design-iterations 2");
  ASSERT_EQ(ex.status, 0) << ex.output;
  const CliRun cal =
      run_dentsim("calibrate " + (d / "log.csv").string() + " --truth " +
                  (s4 / "truth.json").string() + " --json " + (d / "fit.json").string() + " -o " +
                  (d / "model.json").string() + " --max-samples 500");
  ASSERT_EQ(cal.status, 0) << cal.output;
  const nlohmann::json f = read_json_file(d / "fit.json");
  const SeedResult& r = lib.result;
  EXPECT_EQ(f.at("identifiable_count").get<int>(), r.identifiable);
  EXPECT_EQ(f.at("model_mismatch").get<bool>(), r.model_mismatch);
  EXPECT_EQ(f.at("truth_model_error").at("fitted").at("mass_matrix").get<double>(),
            r.fitted.mass_matrix);
  EXPECT_EQ(f.at("truth_model_error").at("prior").at("gravity").get<double>(), r.prior.gravity);
  ASSERT_EQ(f.at("parameters").size(), r.params.size());
  for (std::size_t i = 0; i < r.params.size(); ++i) {
    const nlohmann::json& e = f.at("parameters")[i];
    EXPECT_EQ(e.at("name").get<std::string>(), r.params[i].name);
    EXPECT_EQ(e.at("value").get<double>(), r.params[i].value) << r.params[i].name;
    EXPECT_EQ(e.at("std").get<double>(), r.params[i].std) << r.params[i].name;
    if (r.params[i].identifiable) {
      EXPECT_EQ(e.at("rel_error").get<double>(), r.params[i].rel_error) << r.params[i].name;
      EXPECT_EQ(e.at("error_over_std").get<double>(), r.params[i].error_over_std);
    }
  }
  // The same fitted model, named after the log it came from (issue #33: the CLI's names the log
  // file, the library's the seed); every number identical.
  nlohmann::json cli_model = nlohmann::json::parse(file_text(d / "model.json"));
  nlohmann::json lib_model = nlohmann::json::parse(file_text(s4 / "model.json"));
  EXPECT_NE(cli_model.at("name").get<std::string>().find("(fitted from "), std::string::npos);
  EXPECT_NE(lib_model.at("name").get<std::string>().find("(fitted from "), std::string::npos);
  cli_model.erase("name");
  lib_model.erase("name");
  EXPECT_EQ(cli_model, lib_model);
  fs::remove_all(d);
}

TEST(CalibrateSeedsCli, BadFlagsExitTwoNamingTheFlagAndWriteNothing) {
  namespace fs = std::filesystem;
  const fs::path d = fresh_temp_dir("dentsim_calibrate_seeds_bad");
  const std::string json = " --json " + (d / "x.json").string();
  const struct {
    std::string args, names;
  } cases[] = {
      {"--count 0", "--count"},
      {"--duration 0.5", "--duration"},
      {"--duration nan", "--duration"},
      {"--duration 3 --lowpass 1", "--lowpass"},
      {"--lowpass 600", "--lowpass"},
      {"--first 18446744073709551615 --count 2", "--first"},
      {"--device " + (d / "missing.json").string(), "missing.json"},
      {"--out " + (d / "plain" / "sub").string(), "--out"},
  };
  write_file_atomic((d / "plain").string(), "a file, not a directory\n");
  for (const auto& c : cases) {
    const CliRun r = run_dentsim("calibrate-seeds " + c.args + json);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.names), std::string::npos) << c.args << ": " << r.output;
    EXPECT_FALSE(fs::exists(d / "x.json")) << c.args;
  }
  fs::remove_all(d);
}

// `mpirun -n 2 dentsim calibrate-seeds` writes the JSON one process writes (issue #20). Skipped
// when the binary has no MPI (`dentsim info` says "MPI: no").
TEST(CalibrateSeedsCli, TwoRanksWriteTheJsonOfOneProcess) {
  namespace fs = std::filesystem;
  const CliRun info = run_dentsim("info");
  const std::string key = "; launcher ";
  const std::size_t at = info.output.find(key);
  if (info.output.find("  MPI: yes") == std::string::npos || at == std::string::npos) {
    GTEST_SKIP() << "dentsim built without MPI";
  }
  const std::string mpiexec =
      info.output.substr(at + key.size(), info.output.find(')', at) - at - key.size());
  const fs::path d = fresh_temp_dir("dentsim_calibrate_seeds_mpi");
  const std::string args =
      " calibrate-seeds --first 7 --count 3 --duration 2 --design-iterations 0 "
      "--max-samples 300 --json ";
  const CliRun one = run_dentsim(args + (d / "one.json").string());
  ASSERT_EQ(one.status, 0) << one.output;
  // As tests/cli/mpi_sweep_test.cc: root allowed, shared memory only, no binding, a timeout.
  const std::string cmd =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader "
      "OMPI_MCA_btl_vader_single_copy_mechanism=none timeout 300 " +
      mpiexec + " -n 2 --oversubscribe --bind-to none " + std::string(DENTSIM_BINARY) + args +
      (d / "two.json").string() + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (p && std::fgets(buf, sizeof buf, p)) out += buf;
  const int st = p ? pclose(p) : -1;
  ASSERT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << out;
  const nlohmann::json a = read_json_file(d / "one.json"), b = read_json_file(d / "two.json");
  ASSERT_EQ(a.at("seeds").size(), 3u);
  EXPECT_EQ(a, b) << nlohmann::json::diff(a, b).dump(1);
  // Rank 1 ran seed 8: its progress line came through, the table once (rank 0).
  EXPECT_NE(out.find("(rank 1)"), std::string::npos) << out;
  EXPECT_EQ(out.find("| std reported"), out.rfind("| std reported")) << out;
  fs::remove_all(d);
}

}  // namespace
}  // namespace dentsim
