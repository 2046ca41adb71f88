// Open-loop replay (sim/session_replay.h, `dentsim replay`): a session recorded from a closed
// loop of the reference pipeline on the simulated Phantom replays through the same pipeline bit
// for bit (torque difference exactly 0), and a known perturbation of one recorded command is
// reported exactly, at its tick.
#include "sim/session_replay.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "device/closed_loop.h"
#include "device/phantom_device.h"
#include "device/scripted_hand.h"
#include "reference/phantom/phantom_model.h"
#include "tests/support/cli.h"

namespace dentsim {
namespace {

// Records `ticks` ticks of the free-space reference pipeline driving the simulated Phantom, moved
// by the scripted hand.
std::string record_free_space(const std::string& name, int ticks) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("dentsim_replay_" + std::to_string(::getpid()) + "_" + name))
                               .string();
  const PhantomParams params = default_phantom_params();
  const PhantomModel model(params);
  SimulatedPhantom device(phantom_plant(params), phantom_device_config(params),
                          phantom_home_q(params));
  // A hand moving the tool 1 cm along x in 0.2 s, so the coupling has work to do.
  const Pose home = model.forward_kinematics(phantom_home_q(params));
  std::vector<HandKeyframe> keys(2);
  keys[0].x_ref = home.x;
  keys[1].t = 0.2;
  keys[1].x_ref = home.x + Vec3(0.01, 0.0, 0.0);
  const ScriptedHand hand(HandImpedance{}, keys, home.R);
  device.set_hand(&hand);
  ReferencePipeline pipeline(model, free_space_pipeline_config(params.torque_limit_n_m));
  NoContacts contacts;
  ClosedLoop loop(device, pipeline, contacts);
  SessionHeader h;
  h.dof = 6;
  h.tick_rate_hz = 1.0 / device.capabilities().nominal_period;
  h.context = "{\"pipeline\":\"reference\",\"contacts\":\"none\"}";
  SessionWriter w(path, h);
  loop.start();
  for (int k = 0; k < ticks; ++k) {
    // The per-tick call (the sample the tick ran on, the command it produced, its contacts).
    const DeviceSample s = loop.sample();
    const TickResult& r = loop.step();
    EXPECT_TRUE(w.push(static_cast<std::uint64_t>(k), s, r.tau,
                       static_cast<std::uint32_t>(r.contacts.size())));
  }
  w.stop();
  EXPECT_EQ(device.faults(), kFaultNone);
  return path;
}

TEST(SessionReplay, SamePipelineReproducesTheRecordingExactly) {
  const std::string path = record_free_space("exact", 300);
  const Session s = read_session(path);
  ASSERT_EQ(s.records.size(), 300u);
  // The recording is not trivial: the commands vary.
  double spread = 0.0;
  for (const SessionRecord& r : s.records) {
    spread = std::max(spread, (r.tau - s.records.front().tau).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(spread, 1e-4);

  const ReplayResult r = replay_free_space_reference(s);
  EXPECT_EQ(r.ticks, 300);
  EXPECT_EQ(r.max_torque_diff_n_m, 0.0);
  EXPECT_EQ(r.max_force_diff_n, 0.0);
  EXPECT_EQ(r.contact_count_mismatches, 0);

  // The CLI on the same file.
  const std::string json = path + ".json";
  const auto cli = testing::run_dentsim("replay " + path + " --pipeline reference --json " + json);
  ASSERT_EQ(cli.status, 0) << cli.output;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["ticks"], 300);
  EXPECT_EQ(j["max_torque_diff_n_m"], 0.0);
  EXPECT_EQ(j["max_force_diff_n"], 0.0);
  std::filesystem::remove(json);
  std::filesystem::remove(path);
}

TEST(SessionReplay, APerturbedCommandIsFoundAtItsTick) {
  const std::string path = record_free_space("perturbed", 100);
  Session s = read_session(path);
  const double delta = 1.0 / 1024;
  s.records[37].tau[2] += delta;
  const ReplayResult r = replay_free_space_reference(s);
  const PhantomModel model(default_phantom_params());
  EXPECT_EQ(r.worst_tick, 37);
  // |tau_rec + delta - tau_rec| to one rounding of tau_rec + delta (|tau| < 1 N m).
  EXPECT_NEAR(r.max_torque_diff_n_m, delta, 1.2e-16);
  // The force the difference makes: |f| of J1^T (0, 0, delta, 0, 0, 0) at that sample.
  const Vec6 dtau = (Vec6() << 0, 0, delta, 0, 0, 0).finished();
  const double f =
      (model.twist_to_joint(s.records[37].sample.q).transpose() * dtau).head<3>().norm();
  EXPECT_NEAR(r.max_force_diff_n, f, 1e-12 * f);
  std::filesystem::remove(path);
}

TEST(SessionReplay, CorruptFileIsBadInput) {
  const std::string path = record_free_space("corrupt", 10);
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 3);
  const auto cli = testing::run_dentsim("replay " + path);
  EXPECT_EQ(cli.status, 2) << cli.output;
  EXPECT_NE(cli.output.find("session " + path + ": truncated record 9"), std::string::npos)
      << cli.output;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace dentsim
