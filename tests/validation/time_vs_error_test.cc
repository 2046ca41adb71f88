// Run time against error (validation/time_vs_error.h, `dentsim bench`, issue #14): the finest
// run's own error is exactly zero, the fast pipeline at the reference's settings agrees with it to
// round-off until the first discrete drilling event, the error falls as the servo rate rises
// toward the finest run's, and the command's JSON keeps the keys.
#include "validation/time_vs_error.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "reference/core/io.h"
#include "tests/support/cli.h"

namespace dentsim {
namespace {

const BenchVariant& variant(const TimeVsErrorResult& r, const std::string& name) {
  for (const BenchVariant& v : r.variants) {
    if (v.name == name) return v;
  }
  ADD_FAILURE() << "no variant " << name;
  return r.variants.front();
}

TEST(TimeVsError, FastAgreesWithTheReferenceAtTheSameSettingsUntilTheCutDiverges) {
  TimeVsErrorConfig c;
  // The tool reaches the tooth at ~1.1 s. At the built-in drill's quiet gains (K_tooth 3000 N/m,
  // the encoder Kalman filter; issue #29) the two agree to 1.6e-12 N up to 1.2 s and part by
  // 0.16 N before 1.25 s, with the same removed volume (`dentsim bench --duration D --variants
  // fast@1kHz/r128 --reference-tick-hz 1000 --reference-resolution 128`): a discrete event whose
  // cause is not identified yet (at K_tooth 12000 the first tie was at 1.307 s).
  c.duration_s = 1.2;
  c.finest = BenchSettings{"reference", 1000.0, 128, false};
  c.only = {"fast@1kHz/r128"};
  const TimeVsErrorResult r = run_time_vs_error(c);
  ASSERT_EQ(r.variants.size(), 2u);
  EXPECT_EQ(r.reference_variant, "reference@1kHz/r128");
  const BenchVariant& ref = variant(r, "reference@1kHz/r128");
  EXPECT_EQ(ref.force_rms_error_n, 0.0);
  EXPECT_EQ(ref.force_max_error_n, 0.0);
  EXPECT_EQ(ref.force_max_error_raw_n, 0.0);
  EXPECT_EQ(ref.removed_volume_error_mm3, 0.0);
  const BenchVariant& fast = variant(r, "fast@1kHz/r128");
  EXPECT_EQ(fast.ticks, ref.ticks);
  // Signal guard: the tool touches (forces of a newton) while the two agree to round-off.
  EXPECT_GT(ref.max_force_n, 0.3);
  EXPECT_LT(fast.force_max_error_raw_n, 1e-9);
  EXPECT_LT(fast.force_max_error_n, 1e-9);
  EXPECT_LE(fast.removed_volume_error_mm3, 1e-12);
}

// The same with the field model (`--contact-model field`): both pipelines edit the field at the
// same fixed latency (make_reference_tooth, fast/tooth/field.h), so they render the same contact
// while the tool touches the tooth, and the finest run is the reference's at the same model.
TEST(TimeVsError, FastAgreesWithTheReferenceOnTheFieldModel) {
  TimeVsErrorConfig c;
  c.duration_s = 1.2;
  c.contact_model = "field";
  c.finest = BenchSettings{"reference", 1000.0, 128, false};
  c.only = {"fast@1kHz/r128"};
  const TimeVsErrorResult r = run_time_vs_error(c);
  ASSERT_EQ(r.variants.size(), 2u);
  const BenchVariant& ref = variant(r, "reference@1kHz/r128");
  const BenchVariant& fast = variant(r, "fast@1kHz/r128");
  EXPECT_EQ(fast.ticks, ref.ticks);
  EXPECT_GT(ref.max_force_n, 0.3);  // in contact
  EXPECT_LT(fast.force_max_error_raw_n, 1e-9);
  EXPECT_LE(fast.removed_volume_error_mm3, 1e-12);
  EXPECT_EQ(time_vs_error_json(r)["contact_model"], "field");
  // An unknown model is the scene loader's input error, naming the run.
  TimeVsErrorConfig bad = c;
  bad.contact_model = "voxels";
  EXPECT_THROW(run_time_vs_error(bad), InputError);
}

TEST(TimeVsError, ForceErrorFallsAsTheServoRateRisesTowardTheFinest) {
  // Free space before the tool reaches the tooth (no discrete event): the hand-felt force
  // (10 ms mean) converges with the rate; the finest run at 8 kHz.
  TimeVsErrorConfig c;
  c.duration_s = 0.9;
  c.finest = BenchSettings{"reference", 8000.0, 64, false};
  c.base.resolution = 64;
  c.only = {"fast@1kHz/r64", "fast@2kHz/r64", "fast@4kHz/r64"};
  const TimeVsErrorResult r = run_time_vs_error(c);
  const double e1 = variant(r, "fast@1kHz/r64").force_rms_error_n;
  const double e2 = variant(r, "fast@2kHz/r64").force_rms_error_n;
  const double e4 = variant(r, "fast@4kHz/r64").force_rms_error_n;
  std::printf("force RMS error (10 ms mean) vs 8 kHz: 1 kHz %.4g N, 2 kHz %.4g N, 4 kHz %.4g N\n",
              e1, e2, e4);
  EXPECT_GT(e1, 0.0);
  EXPECT_GT(e1, e2);
  EXPECT_GT(e2, e4);
  // More ticks per simulated second cost proportionally more servo time.
  EXPECT_EQ(variant(r, "fast@4kHz/r64").ticks, 4 * variant(r, "fast@1kHz/r64").ticks);
}

TEST(TimeVsError, UnknownVariantAndBadSettingsAreInputErrors) {
  TimeVsErrorConfig c;
  c.only = {"fast@3kHz/r128"};
  EXPECT_THROW(run_time_vs_error(c), InputError);
  TimeVsErrorConfig d;
  d.finest.resolution = 100;
  EXPECT_THROW(run_time_vs_error(d), InputError);
  TimeVsErrorConfig e;
  e.base.pipeline = "reference";
  e.base.float_device_terms = true;
  EXPECT_THROW(run_time_vs_error(e), InputError);
  // Every variant is the base with one setting changed; names are unique.
  const std::vector<std::string> names = time_vs_error_variant_names(TimeVsErrorConfig{});
  EXPECT_EQ(names.front(), "reference@8kHz/r512");
  for (std::size_t i = 0; i < names.size(); ++i) {
    for (std::size_t j = i + 1; j < names.size(); ++j) EXPECT_NE(names[i], names[j]);
  }
}

TEST(TimeVsError, CommandWritesTheContractKeysAndThePlot) {
  namespace fs = std::filesystem;
  const fs::path d = fs::temp_directory_path() / "dentsim_bench_cli_test";
  fs::remove_all(d);
  fs::create_directories(d);
  const auto r = testing::run_dentsim(
      "bench --duration 0.3 --reference-tick-hz 2000 --reference-resolution 64 --variants "
      "fast@1kHz/r128 --json " +
      (d / "bench.json").string() + " --out " + d.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream f(d / "bench.json");
  ASSERT_TRUE(f.good());
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["reference_variant"], "reference@2kHz/r64");
  ASSERT_EQ(j["variants"].size(), 2u);
  for (const auto& v : j["variants"]) {
    for (const char* key : {"tick_us_median", "tick_us_p99", "force_rms_error_n",
                            "force_max_error_n", "removed_volume_error_mm3"}) {
      ASSERT_TRUE(v.contains(key)) << key;
      EXPECT_TRUE(v[key].is_number()) << key;
      EXPECT_GE(v[key].get<double>(), 0.0) << key;
    }
    EXPECT_TRUE(v["name"].is_string());
    EXPECT_TRUE(v["settings"].is_object());
    EXPECT_LE(v["tick_us_median"].get<double>(), v["tick_us_p99"].get<double>());
  }
  EXPECT_GT(fs::file_size(d / "pareto.png"), 1000u);
  EXPECT_TRUE(fs::exists(d / "time_vs_error.md"));
  const auto bad = testing::run_dentsim("bench --variants nope --out " + (d / "x").string());
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("unknown variant 'nope'"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace dentsim
