// Sweeps over MPI (cli/mpi_sweep.h, issue #20; docs/scaling.md): `mpirun -n 2 dentsim zwidth` and
// `mpirun -n 2 dentsim bench` write the JSON one process writes, number for number (exact
// equality: every job's result travels as JSON, whose doubles round-trip bit for bit), and the
// figures of `zwidth --out` (drawn from the re-runs' traces) byte for byte; a job that fails on
// one rank only makes the whole run exit with status 2 and the job's message, without hanging;
// a command that is not a sweep refuses to run on two ranks. Skipped only when the binary is
// built without MPI (`dentsim info` says so); the two ranks share the machine (--oversubscribe).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/support/cli.h"
#include "validation/zwidth_experiment.h"

namespace {

namespace fs = std::filesystem;
using dentsim::testing::CliRun;
using dentsim::testing::fresh_temp_dir;
using dentsim::testing::read_json_file;
using dentsim::testing::run_dentsim;

CliRun run_shell(const std::string& cmd) {
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  std::string out;
  char buf[4096];
  while (p && std::fgets(buf, sizeof buf, p)) out += buf;
  const int st = p ? pclose(p) : -1;
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

// The launcher `dentsim info` names ("  MPI: yes (Open MPI v4.1.4; launcher /usr/bin/mpiexec)"),
// empty when the binary has no MPI.
std::string launcher() {
  const CliRun info = run_dentsim("info");
  const std::string key = "; launcher ";
  const std::size_t at = info.output.find(key);
  if (info.status != 0 || info.output.find("  MPI: yes") == std::string::npos ||
      at == std::string::npos) {
    return "";
  }
  const std::size_t end = info.output.find(')', at);
  return info.output.substr(at + key.size(), end - at - key.size());
}

// `dentsim ARGS` on two ranks of this machine. Open MPI as root in a container: allowed as root,
// shared memory between the ranks (no network, no single-copy ptrace, which containers forbid),
// no core binding (other processes share the two cores); `timeout` so that a hang fails the test
// instead of the suite.
CliRun run_two_ranks(const std::string& mpiexec, const std::string& args) {
  return run_shell(
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader "
      "OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1 "
      "timeout 120 " +
      mpiexec + " -n 2 --oversubscribe --bind-to none " + std::string(DENTSIM_BINARY) + " " + args);
}

#define SKIP_WITHOUT_MPI(mpiexec)                                                             \
  if (mpiexec.empty()) {                                                                      \
    GTEST_SKIP() << "this dentsim is built without MPI (`dentsim info`: MPI: no): configure " \
                    "with -DDENTSIM_MPI=ON and libopenmpi-dev installed";                     \
  }

// Drops the wall-clock fields of `dentsim bench` (tick times of whichever core ran the job) and
// what the threads' scheduling sets (how many field edits the servo stood in for the worker).
void drop_wall_clock(nlohmann::json& j) {
  for (nlohmann::json& v : j["variants"]) {
    for (const char* k : {"tick_us_median", "tick_us_p99", "tick_us_mean", "servo_tick_us_median",
                          "servo_tick_us_p99", "field_edit_servo_takeovers",
                          "field_edit_worker_waits", "cpu_s_per_simulated_s"})
      v.erase(k);
  }
}

std::string file_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// The jobs' wire format (what a rank sends; one process takes the same path): dumped to text and
// parsed back, every double comes back bit for bit, including those JSON has no number for.
TEST(MpiSweepWire, ZwidthPointsAndTracesRoundTripBitForBit) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> odd = {
      nan, -nan, inf, -inf, -0.0, 5e-324, 0.1 + 0.2, std::numeric_limits<double>::max(), 1.0 / 3.0};
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  dentsim::ZwidthPoint p;
  p.gains = {odd[6], odd[4], odd[8]};
  p.stable = true;
  p.z_width_n_per_m = odd[0];
  for (std::size_t i = 0; i < odd.size(); ++i) {
    dentsim::ZwidthRun r;
    r.growth_rate_per_s = odd[i];
    r.energy_max_j = odd[(i + 1) % odd.size()];
    r.release_detected_after_s = odd[(i + 2) % odd.size()];
    r.faults = 0xFFFFFFFFu - static_cast<std::uint32_t>(i);
    r.grip_switches = -static_cast<int>(i);
    r.contact = i % 2 == 0;
    r.passive = i % 3 == 0;
    r.quiet = i % 2 == 1;
    if (i % 2 == 0) r.quiet_measures.ripple_device_force = odd[i];  // odd i: no ripple (null)
    r.quiet_measures.contact_losses = static_cast<int>(i);
    p.runs.push_back(r);
  }
  const dentsim::ZwidthPoint q = dentsim::zwidth_point_from_wire(
      nlohmann::json::parse(dentsim::zwidth_point_to_wire(p).dump()));
  EXPECT_EQ(bits(q.gains.k_vc), bits(p.gains.k_vc));
  EXPECT_EQ(bits(q.gains.b_vc), bits(p.gains.b_vc));
  EXPECT_EQ(bits(q.gains.k_tooth), bits(p.gains.k_tooth));
  EXPECT_EQ(bits(q.z_width_n_per_m), bits(p.z_width_n_per_m));
  EXPECT_EQ(q.stable, p.stable);
  EXPECT_EQ(q.passive, p.passive);
  ASSERT_EQ(q.runs.size(), p.runs.size());
  for (std::size_t i = 0; i < p.runs.size(); ++i) {
    EXPECT_EQ(bits(q.runs[i].growth_rate_per_s), bits(p.runs[i].growth_rate_per_s)) << i;
    EXPECT_EQ(bits(q.runs[i].energy_max_j), bits(p.runs[i].energy_max_j)) << i;
    EXPECT_EQ(bits(q.runs[i].release_detected_after_s), bits(p.runs[i].release_detected_after_s))
        << i;
    EXPECT_EQ(q.runs[i].faults, p.runs[i].faults) << i;
    EXPECT_EQ(q.runs[i].grip_switches, p.runs[i].grip_switches) << i;
    EXPECT_EQ(q.runs[i].contact, p.runs[i].contact) << i;
    EXPECT_EQ(q.runs[i].passive, p.runs[i].passive) << i;
    EXPECT_EQ(q.runs[i].quiet, p.runs[i].quiet) << i;
    EXPECT_EQ(q.runs[i].quiet_measures.contact_losses, p.runs[i].quiet_measures.contact_losses);
    ASSERT_EQ(q.runs[i].quiet_measures.ripple_device_force.has_value(), i % 2 == 0) << i;
    if (i % 2 == 0) {
      EXPECT_EQ(bits(*q.runs[i].quiet_measures.ripple_device_force), bits(odd[i])) << i;
    }
  }
  dentsim::ZwidthTrace t;
  t.t = odd;
  t.penetration_m = {odd.rbegin(), odd.rend()};
  t.grip_state = {1, 0, -1};
  const dentsim::ZwidthTrace u = dentsim::zwidth_trace_from_wire(
      nlohmann::json::parse(dentsim::zwidth_trace_to_wire(t).dump()));
  ASSERT_EQ(u.t.size(), t.t.size());
  ASSERT_EQ(u.penetration_m.size(), t.penetration_m.size());
  for (std::size_t i = 0; i < t.t.size(); ++i) {
    EXPECT_EQ(bits(u.t[i]), bits(t.t[i])) << i;
    EXPECT_EQ(bits(u.penetration_m[i]), bits(t.penetration_m[i])) << i;
  }
  EXPECT_EQ(u.grip_state, t.grip_state);
  EXPECT_TRUE(u.force_n.empty());
}

// `dentsim ARGS --json D/one.json [--out D/one]` in one process and the same with two.json (and
// D/two) on two ranks; both must succeed. The JSON documents and the outputs of both.
struct OneAndTwo {
  CliRun one, two;
  nlohmann::json a, b;  // one.json, two.json
};
OneAndTwo run_one_and_two(const std::string& mpiexec, const fs::path& d, const std::string& args,
                          bool with_out) {
  const auto outputs = [&](const std::string& name) {
    std::string o = "--json " + (d / (name + ".json")).string();
    if (with_out) o += " --out " + (d / name).string();
    return o;
  };
  OneAndTwo r;
  r.one = run_dentsim(args + outputs("one"));
  EXPECT_EQ(r.one.status, 0) << r.one.output;
  r.two = run_two_ranks(mpiexec, args + outputs("two"));
  EXPECT_EQ(r.two.status, 0) << r.two.output;
  if (r.one.status == 0 && r.two.status == 0) {
    r.a = read_json_file(d / "one.json");
    r.b = read_json_file(d / "two.json");
  }
  return r;
}

TEST(MpiSweep, ZwidthOnTwoRanksEqualsOneProcess) {
  const std::string mpiexec = launcher();
  SKIP_WITHOUT_MPI(mpiexec);
  const fs::path d = fresh_temp_dir("dentsim_mpi_sweep_zwidth");
  // The simulated Phantom: 2 methods x 2 operators x 2 K_vc (8 closed loops of 5 s contact).
  const std::string args =
      "zwidth --methods explicit pmi-pd --operators force grip --k-vc 400 1600 --b-vc 2 "
      "--k-tooth 3000 --hold 5 --threads 1 ";
  const OneAndTwo r = run_one_and_two(mpiexec, d, args, false);
  ASSERT_FALSE(HasFailure());
  const nlohmann::json &a = r.a, &b = r.b;
  const CliRun& two = r.two;
  ASSERT_EQ(a["methods"]["pmi-pd"]["operators"]["force"]["points"].size(), 2u);
  EXPECT_EQ(a, b) << "diff (one process -> two ranks): " << nlohmann::json::diff(a, b).dump(1);
  // The table is printed once (rank 0), as by one process.
  ASSERT_NE(two.output.find("ratio pmi/explicit"), std::string::npos) << two.output;
  EXPECT_EQ(two.output.find("ratio pmi/explicit"), two.output.rfind("ratio pmi/explicit"))
      << two.output;
  fs::remove_all(d);
}

// The re-runs at the best points: the sensitivity variants (JSON) and the traces and grip
// detector pair (the figures of --out), on the 1-DoF axis testbed (fast), with 2 threads per rank.
TEST(MpiSweep, ZwidthReRunsOnTwoRanksEqualOneProcess) {
  const std::string mpiexec = launcher();
  SKIP_WITHOUT_MPI(mpiexec);
  const fs::path d = fresh_temp_dir("dentsim_mpi_sweep_reruns");
  const std::string args =
      "zwidth --testbed axis --methods pmi-pd --operators force release --k-vc 1600 --b-vc 2 "
      "--k-tooth 1500 3000 --grasp-mass 1 --grip-detector --sensitivity --threads 2 ";
  const OneAndTwo r = run_one_and_two(mpiexec, d, args, true);
  ASSERT_FALSE(HasFailure());
  const nlohmann::json &a = r.a, &b = r.b;
  // The re-runs ran: 11 sensitivity variants of PMI + PD, and its grip detector pair drawn.
  ASSERT_EQ(a["methods"]["pmi-pd"]["sensitivity"].size(), 11u) << a.dump(1);
  EXPECT_EQ(a, b) << "diff (one process -> two ranks): " << nlohmann::json::diff(a, b).dump(1);
  for (const char* png : {"force_vs_penetration.png", "time_series.png", "stability_map.png",
                          "summary.png", "grip_detector.png"}) {
    ASSERT_TRUE(fs::exists(d / "one" / png)) << png;
    EXPECT_EQ(file_bytes(d / "one" / png), file_bytes(d / "two" / png)) << png;
  }
  fs::remove_all(d);
}

TEST(MpiSweep, BenchOnTwoRanksEqualsOneProcessButForTickTimes) {
  const std::string mpiexec = launcher();
  SKIP_WITHOUT_MPI(mpiexec);
  const fs::path d = fresh_temp_dir("dentsim_mpi_sweep_bench");
  const std::string args =
      "bench --duration 1 --reference-tick-hz 2000 --reference-resolution 64 --base-resolution 64 "
      "--variants fast@1kHz/r64 fast-float@1kHz/r64 ";
  OneAndTwo r = run_one_and_two(mpiexec, d, args, true);
  ASSERT_FALSE(HasFailure());
  nlohmann::json &a = r.a, &b = r.b;
  ASSERT_EQ(a["variants"].size(), 3u);  // 3 jobs: 2 on rank 0, 1 on rank 1
  // The variants differ from the yardstick (else the comparison would be vacuous).
  EXPECT_GT(a["variants"][1]["force_rms_error_raw_n"].get<double>(), 0.0);
  drop_wall_clock(a);
  drop_wall_clock(b);
  EXPECT_EQ(a, b) << "diff (one process -> two ranks): " << nlohmann::json::diff(a, b).dump(1);
  fs::remove_all(d);
}

// K_tooth = 0 is refused by the closed loop itself, so only the job of that grid point fails: the
// second of two (index 1: rank 1's). Rank 0 finishes its job, learns of rank 1's failure at the
// gather, and every rank exits with status 2; the message is printed once and no JSON is written.
TEST(MpiSweep, AJobFailingOnOneRankFailsTheRunWithoutHanging) {
  const std::string mpiexec = launcher();
  SKIP_WITHOUT_MPI(mpiexec);
  const fs::path d = fresh_temp_dir("dentsim_mpi_sweep_fail");
  const std::string args =
      "zwidth --testbed axis --methods pmi --operators force --k-vc 400 --b-vc 2 --k-tooth 3000 0 "
      "--threads 1 --json " +
      (d / "z.json").string();
  const std::string message = "zwidth gains: expected k_vc > 0, k_tooth > 0";
  const CliRun one = run_dentsim(args);
  EXPECT_EQ(one.status, 2) << one.output;
  EXPECT_NE(one.output.find(message), std::string::npos) << one.output;
  const CliRun two = run_two_ranks(mpiexec, args);
  EXPECT_EQ(two.status, 2) << two.output;  // not 124: timeout's status when it had to stop it
  const std::size_t at = two.output.find(message);
  EXPECT_NE(at, std::string::npos) << two.output;
  EXPECT_EQ(two.output.find(message, at + 1), std::string::npos) << "printed twice:\n"
                                                                 << two.output;
  EXPECT_FALSE(fs::exists(d / "z.json"));
  fs::remove_all(d);
}

// `dentsim run` is not a sweep: two ranks would simulate the same scene into the same files.
TEST(MpiSweep, RunRefusesTwoRanks) {
  const std::string mpiexec = launcher();
  SKIP_WITHOUT_MPI(mpiexec);
  const fs::path d = fresh_temp_dir("dentsim_mpi_sweep_run");
  const CliRun two =
      run_two_ranks(mpiexec, "run probe --duration 0.1 --out " + (d / "out").string());
  EXPECT_EQ(two.status, 2) << two.output;
  EXPECT_NE(two.output.find("'dentsim run' is not a sweep"), std::string::npos) << two.output;
  EXPECT_FALSE(fs::exists(d / "out" / "report.json"));
  fs::remove_all(d);
}

}  // namespace
