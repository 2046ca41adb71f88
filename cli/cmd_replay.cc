// `dentsim replay FILE --pipeline reference --json OUT`: re-runs a pipeline open-loop on a
// recorded session (sim/session_record.h) and reports how far its torques are from the
// recorded commands (sim/session_replay.h): `ticks`, `max_torque_diff_n_m`,
// `max_force_diff_n`. A session recorded by `dentsim run --record` replays in its scene (the
// scene's pipeline configuration and a fresh copy of its tooth); others in free space on the
// default Phantom model (free_space_pipeline_config()). `--pipeline fast|reference`.
#include <cstdio>
#include <memory>

#include "fast/registry.h"
#include "cli/registry.h"
#include "sim/session_replay.h"
#include "reference/core/io.h"

namespace dentsim::cli {
namespace {

struct ReplayOptions {
  std::string file;
  std::string pipeline = "reference";
  std::string json;
};

void replay(const ReplayOptions& o) {
  const Session session = read_session(o.file);
  bool scene = false;
  const ReplayResult r = replay_recorded_session(session, o.pipeline, &scene);
  const nlohmann::json j = replay_report_json(o.file, o.pipeline, session, r, scene);
  if (!o.json.empty()) write_json(o.json, j);
  std::printf("%s: %ld ticks, max torque diff %.3g N m, max force diff %.3g N\n", o.file.c_str(),
              r.ticks, r.max_torque_diff_n_m, r.max_force_diff_n);
}

void setup_replay(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* sub = app.add_subcommand(
      "replay",
      "Re-run a pipeline open-loop on a recorded session and compare its torques with the\n"
      "recorded commands (differential testing on data recorded from a device)");
  sub->add_option("FILE", o->file, "recorded session (dentsim run ... --record FILE)")->required();
  sub->add_option("--pipeline", o->pipeline, "pipeline to re-run")
      ->check(CLI::IsMember(implementation_names()))
      ->capture_default_str();
  sub->add_option("--json", o->json, "write the comparison as JSON to this file");
  sub->callback([o] { replay(*o); });
}
DENTSIM_REGISTER_COMMAND(setup_replay);

}  // namespace
}  // namespace dentsim::cli
