// End-to-end tests of the command line's limits (issue #18, "validation at the door"): flag values
// that used to hang, run out of memory or write null results are refused with exit status 2 and
// a message naming the flag; the limit is stated in --help; output-path problems are reported
// before any computation, and an existing output is left as it was.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "reference/core/io.h"
#include "tests/support/cli.h"

namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using Cmd = dentsim::testing::CliRun;
inline Cmd run(const std::string& args) { return dentsim::testing::run_dentsim(args); }

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("dentsim_limits_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

struct Case {
  std::string args;    // after "dentsim"
  std::string needle;  // in the message
};

// Every case exits 2 at once (each would otherwise run for minutes, hang or write nulls) and the
// output file written before by a good run is unchanged.
TEST(CliLimits, OutOfRangeFlagsExitTwoNamingTheFlag) {
  const fs::path d = temp_dir("flags");
  const std::string out = (d / "old.json").string();
  std::ofstream(out) << "previous\n";
  const std::string j = " --json " + out;
  const Case cases[] = {
      {"demo --duration 1e9" + j,
       "--duration: expected a finite number in [0.001, 600], got '1e9'"},
      {"demo --tick-ms 1e-9" + j, "--tick-ms: expected a finite number in [0.05, 100]"},
      {"demo --duration nan" + j, "--duration: expected a finite number"},
      {"demo --k-vc inf" + j, "--k-vc: expected a finite number in [1e-06, 1e+07]"},
      {"zwidth --quick --hold inf" + j, "--hold: expected a finite number in [5, 600], got 'inf'"},
      {"zwidth --quick --threads 100000" + j, "--threads"},
      {"run probe --duration 1e6 --out " + (d / "r").string(),
       "--duration: expected a finite number in [0, 3600], got '1e6'"},
      {"voxelize --procedural --resolution 32 --scale 1e308" + j,
       "--scale: expected a finite number in [1e-12, 10], got '1e308'"},
      {"voxelize --procedural --resolution 32 --enamel-mm inf" + j,
       "--enamel-mm: expected a finite number in [0, 10], got 'inf'"},
      {"voxelize --procedural --resolution 32 --size-mm 1e300" + j, "--size-mm"},
      {"crosscheck device --seed -1 --samples 1" + j, "--seed"},
  };
  for (const Case& c : cases) {
    const Cmd r = run(c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.output;
    EXPECT_THAT(r.output, HasSubstr(c.needle)) << c.args;
    EXPECT_EQ(dentsim::read_file(out), "previous\n") << c.args;
  }
  EXPECT_FALSE(fs::exists(d / "r"));
}

TEST(CliLimits, LimitsAreStatedInHelp) {
  EXPECT_THAT(run("demo --help").output, HasSubstr("[0.05, 100]"));
  EXPECT_THAT(run("zwidth --help").output, HasSubstr("[5, 600]"));
  EXPECT_THAT(run("run --help").output, HasSubstr("[0, 3600]"));
  EXPECT_THAT(run("voxelize --help").output, HasSubstr("[1e-12, 10]"));
}

// Output-path problems come before the work (voxelize would otherwise compute first) and name the
// flag; an output that is the input mesh is refused.
TEST(CliLimits, OutputPathsAreCheckedBeforeTheWork) {
  const fs::path d = temp_dir("outputs");
  const std::string missing = (d / "no/such/dir/v.json").string();
  const Cmd a = run("voxelize --procedural --resolution 32 --json " + missing);
  EXPECT_EQ(a.status, 2) << a.output;
  EXPECT_THAT(a.output, HasSubstr("--json '" + missing + "': directory"));
  const std::string x = (d / "x.json").string();
  const Cmd b = run("voxelize --procedural --resolution 32 --json " + x + " --png " + x);
  EXPECT_EQ(b.status, 2) << b.output;
  EXPECT_THAT(b.output, HasSubstr("--png '" + x + "': is also the output --json"));
  EXPECT_FALSE(fs::exists(x));
  const std::string mesh = (d / "t.obj").string();
  std::ofstream(mesh) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  const std::string before = dentsim::read_file(mesh);
  const Cmd c = run("voxelize " + mesh + " --size-mm 10 --resolution 32 --json " + mesh);
  EXPECT_EQ(c.status, 2) << c.output;
  EXPECT_THAT(c.output, HasSubstr("is the input MESH"));
  EXPECT_EQ(dentsim::read_file(mesh), before);
  const Cmd e = run("demo --duration 0.01 --json " + (d / "nodir/d.json").string());
  EXPECT_EQ(e.status, 2) << e.output;
  EXPECT_THAT(e.output, HasSubstr("does not exist"));
}

// A mesh path that is a character device or a FIFO is refused at once instead of hanging.
TEST(CliLimits, MeshThatIsNotARegularFileIsRefused) {
  const fs::path d = temp_dir("fifo");
  fs::create_symlink("/dev/zero", d / "zero.stl");
  const Cmd z = run("voxelize " + (d / "zero.stl").string() +
                    " --size-mm 10 --resolution 32 --json " + (d / "v.json").string());
  EXPECT_EQ(z.status, 2) << z.output;
  EXPECT_THAT(z.output, HasSubstr("it is a character device; expected a regular file"));
  EXPECT_FALSE(fs::exists(d / "v.json"));
}

}  // namespace
