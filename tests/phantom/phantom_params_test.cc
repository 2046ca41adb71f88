// Device model file: defaults, round trip, validation messages, and the `dentsim device` CLI.
#include "reference/phantom/phantom_params.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <regex>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(PhantomParams, DefaultFileRoundTripsExactly) {
  const PhantomParams p = default_phantom_params();
  const std::string text = default_phantom_model_file();
  const PhantomParams back = parse_phantom_params(text, "default");
  EXPECT_TRUE(back == p);
  EXPECT_EQ(phantom_params_to_text(back), text);
  // Published values survive (docs/device_facts.md §2): l1, l2, l3 and the forearm mass.
  EXPECT_EQ(back.l1_m, 0.215);
  EXPECT_EQ(back.l2_m, 0.170);
  EXPECT_EQ(back.l3_m, 0.0325);
  EXPECT_EQ(back.forearm.mass_kg, 0.0202);
}

// Returns the InputError message of parsing `text`, or "" if it parsed.
std::string error_of(const std::string& text) {
  try {
    parse_phantom_params(text, "model.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(PhantomParams, MissingFieldIsNamed) {
  const std::string bad = replace(default_phantom_model_file(),
                                  "\"forearm\": {\"mass_kg\": 0.0202, ", "\"forearm\": {");
  EXPECT_THAT(error_of(bad), AllOf(HasSubstr("model.json"), HasSubstr("bodies.forearm.mass_kg"),
                                   HasSubstr("missing")));
}

TEST(PhantomParams, NegativeMassIsNamed) {
  const std::string bad =
      replace(default_phantom_model_file(), "\"mass_kg\": 0.1906", "\"mass_kg\": -0.1906");
  EXPECT_THAT(error_of(bad), AllOf(HasSubstr("bodies.crank.mass_kg"), HasSubstr("positive"),
                                   HasSubstr("-0.1906")));
}

TEST(PhantomParams, WrongTypeIsNamed) {
  const std::string bad =
      replace(default_phantom_model_file(), "\"l1_m\": 0.215", "\"l1_m\": \"0.215\"");
  EXPECT_THAT(error_of(bad),
              AllOf(HasSubstr("arm.l1_m"), HasSubstr("expected a number"), HasSubstr("string")));
  const std::string bad2 =
      replace(default_phantom_model_file(), "\"coulomb_n_m\": [0.008, ", "\"coulomb_n_m\": [");
  EXPECT_THAT(error_of(bad2), AllOf(HasSubstr("joints.coulomb_n_m"), HasSubstr("6 numbers")));
}

// v_s of the Coulomb law per joint (issue #17): one number stands for all six joints (the files
// written before), six numbers give each joint its own; the file is written back either way, one
// number when all six agree; a bad entry is named with its joint.
TEST(PhantomParams, CoulombSmoothingIsOneNumberOrOnePerJoint) {
  const std::string one = default_phantom_model_file();
  ASSERT_NE(one.find("\"coulomb_smoothing_rad_s\": 0.01,"), std::string::npos);
  EXPECT_EQ(parse_phantom_params(one, "one").coulomb_smoothing_rad_s, Vec6::Constant(0.01));
  const std::string six = replace(one, "\"coulomb_smoothing_rad_s\": 0.01,",
                                  "\"coulomb_smoothing_rad_s\": [0.01, 0.02, 0.03, 0.5, 0.25, 0.0],");
  const PhantomParams p = parse_phantom_params(six, "six");
  Vec6 expected;
  expected << 0.01, 0.02, 0.03, 0.5, 0.25, 0.0;
  EXPECT_EQ(p.coulomb_smoothing_rad_s, expected);
  EXPECT_EQ(phantom_params_to_text(p), six);
  EXPECT_TRUE(parse_phantom_params(phantom_params_to_text(p), "back") == p);
  const std::string bad = replace(one, "\"coulomb_smoothing_rad_s\": 0.01,",
                                  "\"coulomb_smoothing_rad_s\": [0.01, 0.02, 0.03, -0.5, 0.25, 0],");
  EXPECT_THAT(error_of(bad), AllOf(HasSubstr("joints.coulomb_smoothing_rad_s"),
                                   HasSubstr("joint 4"), HasSubstr("-0.5")));
  const std::string five = replace(one, "\"coulomb_smoothing_rad_s\": 0.01,",
                                   "\"coulomb_smoothing_rad_s\": [0.01, 0.02, 0.03, 0.5, 0.25],");
  EXPECT_THAT(error_of(five), AllOf(HasSubstr("joints.coulomb_smoothing_rad_s"),
                                    HasSubstr("6 numbers")));
}

// The smooth sign per joint: absent (the files written before) is tanh on every joint and the
// default file does not carry the key; "erf" or six names round-trip; anything else is named.
TEST(PhantomParams, CoulombSignIsOptionalOneOrSixNames) {
  const std::string text = default_phantom_model_file();
  EXPECT_EQ(text.find("coulomb_sign"), std::string::npos);
  for (CoulombSign c : parse_phantom_params(text, "default").coulomb_sign) {
    EXPECT_EQ(c, CoulombSign::kTanh);
  }
  const std::string key = "\"coulomb_smoothing_rad_s\": 0.01,\n";
  const std::string erf = replace(text, key, key + "    \"coulomb_sign\": \"erf\",\n");
  const PhantomParams pe = parse_phantom_params(erf, "erf");
  for (CoulombSign c : pe.coulomb_sign) EXPECT_EQ(c, CoulombSign::kErf);
  EXPECT_EQ(phantom_params_to_text(pe), erf);
  const std::string mixed = replace(
      text, key,
      key + "    \"coulomb_sign\": [\"tanh\", \"tanh\", \"tanh\", \"erf\", \"erf\", \"tanh\"],\n");
  const PhantomParams pm = parse_phantom_params(mixed, "mixed");
  EXPECT_EQ(pm.coulomb_sign[3], CoulombSign::kErf);
  EXPECT_EQ(pm.coulomb_sign[5], CoulombSign::kTanh);
  EXPECT_EQ(phantom_params_to_text(pm), mixed);
  EXPECT_THAT(error_of(replace(text, key, key + "    \"coulomb_sign\": \"sign\",\n")),
              AllOf(HasSubstr("joints.coulomb_sign"), HasSubstr("\"tanh\" or \"erf\""),
                    HasSubstr("sign")));
  EXPECT_THAT(error_of(replace(text, key, key + "    \"coulomb_sign\": [\"erf\", 3],\n")),
              HasSubstr("joints.coulomb_sign"));
}

TEST(PhantomParams, PhysicallyImpossibleInertiaIsNamed) {
  // The published be moments about the shoulder, as CoM moments, break the triangle inequality.
  const std::string bad = replace(default_phantom_model_file(), "\"inertia_kg_m2\": [0.000745,",
                                  "\"inertia_kg_m2\": [0.000789534784,");
  EXPECT_THAT(error_of(bad),
              AllOf(HasSubstr("bodies.upper_arm.inertia_kg_m2"), HasSubstr("triangle inequality")));
}

TEST(PhantomParams, NonPositiveDefiniteMassMatrixIsNamed) {
  // A roll body with (numerically) no inertia and no rotor: M(q) is singular along q6.
  PhantomParams p = default_phantom_params();
  p.gimbal_roll.inertia_kg_m2 = Vec3(1e-30, 1e-30, 1e-30);
  p.gimbal_roll.com_m.setZero();
  p.armature_kg_m2(5) = 0.0;
  const std::string bad = phantom_params_to_text(p);
  EXPECT_THAT(error_of(bad), AllOf(HasSubstr("joints.armature_kg_m2[5]"),
                                   HasSubstr("bodies.gimbal_roll.inertia_kg_m2"),
                                   HasSubstr("not positive definite")));
}

TEST(PhantomParams, OtherBadInputs) {
  EXPECT_THAT(error_of("{ not json"), AllOf(HasSubstr("model.json"), HasSubstr("not valid JSON")));
  EXPECT_THAT(error_of(replace(default_phantom_model_file(), "\"gimbal\": {",
                               "\"gimbal\": {\"extra\": 1, ")),
              HasSubstr("gimbal.extra: unknown field"));
  EXPECT_THAT(error_of(replace(default_phantom_model_file(), "\"q_max_rad\": [0.9,",
                               "\"q_max_rad\": [-1.9,")),
              HasSubstr("joints.q_max_rad[0]"));
  EXPECT_THAT(error_of(replace(default_phantom_model_file(), "\"yaw_axis\": [0.0, 1.0, 0.0]",
                               "\"yaw_axis\": [0.0, 2.0, 0.0]")),
              AllOf(HasSubstr("gimbal.yaw_axis"), HasSubstr("unit vector")));
  EXPECT_THAT(error_of(replace(default_phantom_model_file(), "\"version\": 1", "\"version\": 7")),
              HasSubstr("version"));
  EXPECT_THROW(load_phantom_params("/nonexistent/phantom.json"), InputError);
}

// The model file is read by the one JSON reader (reference/core/json_reader.h): its checks at the
// door apply here too (issue #18: these used to crash or be taken silently).
TEST(PhantomParams, ReaderChecksAtTheDoor) {
  std::string deep = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_THAT(error_of(deep), AllOf(HasSubstr("model.json"), HasSubstr("nested deeper than 64")));
  EXPECT_EQ(error_of(replace(default_phantom_model_file(), "\"l1_m\": 0.215",
                             "\"l1_m\": 1e400")),
            "model.json: arm.l1_m: number '1e400' is outside the range of a double (|x| < 1.8e308)");
  EXPECT_EQ(error_of(replace(default_phantom_model_file(), "\"l1_m\": 0.215",
                             "\"l1_m\": 0.215, \"l1_m\": 0.3")),
            "model.json: arm.l1_m: key given twice in one object (JSON would silently keep the "
            "last)");
  EXPECT_EQ(error_of(replace(default_phantom_model_file(), "\"version\": 1",
                             "\"version\": 4294967297")),
            "model.json: version: expected an integer in [0, 1000], got 4294967297");
  EXPECT_THAT(error_of(replace(default_phantom_model_file(), "\"gravity_m_s2\": 9.81",
                               "\"gravity_m_s2\": \"9.81\"")),
              HasSubstr("model.json: gravity_m_s2: expected a number, got string"));
  EXPECT_THAT(error_of(replace(default_phantom_model_file(), "\"q_max_rad\": [0.9,",
                               "\"q_max_rad\": [null,")),
              HasSubstr("model.json: joints.q_max_rad[0]: expected a finite number"));
}

// ---- CLI: dentsim device show / check ----------------------------------------------------------

struct RunResult {
  int status = -1;
  std::string out;
};

RunResult run(const std::string& args) {
  const std::string cmd = std::string(DENTSIM_BINARY) + " " + args;
  RunResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int st = pclose(pipe);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("dentsim_phantom_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

TEST(DeviceCli, ShowPrintsTheDefaultWhichReloadsToTheSameParams) {
  const RunResult r = run("device show");
  ASSERT_EQ(r.status, 0);
  EXPECT_EQ(r.out, default_phantom_model_file());
  EXPECT_TRUE(parse_phantom_params(r.out, "stdout") == default_phantom_params());
  // show FILE prints the file's model: start a new device from the default and re-show it.
  PhantomParams p = default_phantom_params();
  p.name = "my device";
  p.forearm.mass_kg = 0.025;
  const std::string path = temp_path("mine.json");
  write_file_atomic(path, phantom_params_to_text(p));
  const RunResult r2 = run("device show " + path);
  ASSERT_EQ(r2.status, 0);
  EXPECT_TRUE(parse_phantom_params(r2.out, "stdout") == p);
  std::filesystem::remove(path);
}

TEST(DeviceCli, CheckAcceptsGoodAndRejectsBadNamingTheField) {
  const std::string good = temp_path("good.json");
  const std::string bad = temp_path("bad.json");
  write_file_atomic(good, default_phantom_model_file());
  write_file_atomic(
      bad, replace(default_phantom_model_file(), "\"mass_kg\": 0.0249", "\"mass_kg\": -1"));
  const RunResult ok = run("device check " + good + " 2>&1");
  EXPECT_EQ(ok.status, 0);
  EXPECT_THAT(ok.out, HasSubstr("valid"));
  EXPECT_EQ(run("device check " + good + " --workspace-samples 5000 2>&1").status, 0);
  EXPECT_EQ(run("device check " + good + " --workspace-samples -3 2>&1").status, 2);
  const RunResult ko = run("device check " + bad + " 2>&1");
  EXPECT_EQ(ko.status, 2);
  EXPECT_THAT(ko.out, AllOf(HasSubstr(bad), HasSubstr("bodies.parallel_link.mass_kg")));
  const RunResult missing = run("device check 2>&1");
  EXPECT_EQ(missing.status, 2);
  // A model file nested 10^5 levels deep used to crash device check/show (issue #18).
  const std::string deep = temp_path("deep.json");
  std::string nested;
  for (int i = 0; i < 100000; ++i) nested += "{\"a\": ";
  write_file_atomic(deep, nested + "1" + std::string(100000, '}'));
  for (const char* cmd : {"device check ", "device show "}) {
    const RunResult d = run(cmd + deep + " 2>&1");
    EXPECT_EQ(d.status, 2) << cmd;
    EXPECT_THAT(d.out, AllOf(HasSubstr(deep), HasSubstr("nested deeper than 64"))) << cmd;
  }
  // Valid only if `run` can build the simulated device from it: masses of 1e-20 kg pass the
  // model's checks but MuJoCo refuses them (mjMINVAL); device check used to call them valid.
  PhantomParams tiny = default_phantom_params();
  for (PhantomBody* b : {&tiny.base, &tiny.upper_arm, &tiny.forearm, &tiny.crank,
                         &tiny.parallel_link, &tiny.gimbal_yaw, &tiny.gimbal_pitch,
                         &tiny.gimbal_roll}) {
    b->mass_kg = 1e-20;
    b->inertia_kg_m2 = Vec3::Constant(1e-20);
  }
  const std::string tiny_path = temp_path("tiny.json");
  write_file_atomic(tiny_path, phantom_params_to_text(tiny));
  const RunResult t = run("device check " + tiny_path + " 2>&1");
  EXPECT_EQ(t.status, 2) << t.out;
  EXPECT_THAT(t.out, AllOf(HasSubstr(tiny_path), HasSubstr("the simulated device cannot be built"),
                           HasSubstr("mjMINVAL")));
  std::filesystem::remove(tiny_path);
  // Not a regular file: refused at once instead of reading forever.
  const RunResult z = run("device check /dev/zero 2>&1");
  EXPECT_EQ(z.status, 2);
  EXPECT_THAT(z.out, HasSubstr("'/dev/zero': it is a character device; expected a regular file"));
  std::filesystem::remove(deep);
  std::filesystem::remove(good);
  std::filesystem::remove(bad);
}

}  // namespace
}  // namespace dentsim
