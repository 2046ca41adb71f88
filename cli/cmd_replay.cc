// `dentsim replay FILE --pipeline reference --json OUT`: re-runs a pipeline open-loop on a
// recorded session (sim/session_record.h) and reports how far its torques are from the
// recorded commands (sim/session_replay.h): `ticks`, `max_torque_diff_n_m`,
// `max_force_diff_n`. A session recorded by `dentsim run --record` replays in its scene (the
// scene's pipeline configuration and a fresh copy of its tooth); others in free space on the
// default Phantom model (free_space_pipeline_config()). `--pipeline fast|reference`.
#include <cstdio>
#include <memory>

#include "cli/outputs.h"
#include "cli/registry.h"
#include "cli/verdict.h"
#include "fast/registry.h"
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
  check_outputs({{"--json", o.json}}, {}, {{"FILE", o.file}});
  const Session session = read_session(o.file);
  bool scene = false;
  const ReplayResult r = replay_recorded_session(session, o.pipeline, &scene);
  nlohmann::json j = replay_report_json(o.file, o.pipeline, session, r, scene);
  std::printf("%s: %ld ticks, max torque diff %.3g N m, max force diff %.3g N\n", o.file.c_str(),
              r.ticks, r.max_torque_diff_n_m, r.max_force_diff_n);
  // The verdict. The pipeline that recorded the session must reproduce its commands bit for bit.
  // The other one agrees to kReplayAgreementN until a discrete event parts them (a voxel removed
  // one tick apart, docs/results/fast_crosscheck.md), which only contact can cause: it passes when
  // it agreed at least through the first contact tick; what follows the parting is reported, not
  // bounded.
  std::string recorded;  // the recording pipeline, from the session's context ("" if unknown)
  try {
    const nlohmann::json c = nlohmann::json::parse(session.header.context);
    if (c.is_object() && c.contains("pipeline") && c["pipeline"].is_string())
      recorded = c["pipeline"].get<std::string>();
  } catch (const nlohmann::json::exception&) {
    recorded.clear();  // not a context dentsim wrote: judged as another pipeline
  }
  long first_contact = -1;
  for (std::size_t k = 0; k < session.records.size() && first_contact < 0; ++k) {
    if (session.records[k].contacts > 0) first_contact = static_cast<long>(k);
  }
  const double hz = session.header.tick_rate_hz > 0 ? session.header.tick_rate_hz : 1.0;
  if (r.first_divergent_tick >= 0) {
    std::printf(
        "  first divergent tick %ld (t = %.4f s): force diff above %.0e N from there; "
        "before it at most %.3g N\n",
        r.first_divergent_tick, r.first_divergent_tick / hz, kReplayAgreementN,
        r.max_force_diff_before_divergence_n);
  } else {
    std::printf("  never diverged: every tick within %.0e N\n", kReplayAgreementN);
  }
  Verdict v("replay");
  v.require("ticks compared", r.ticks > 0, std::to_string(r.ticks) + " ticks");
  if (recorded == o.pipeline) {
    v.check("max torque diff (same pipeline: bit for bit)", r.max_torque_diff_n_m, 0.0, "N m");
  } else {
    v.check("force diff before the first divergent tick", r.max_force_diff_before_divergence_n,
            kReplayAgreementN, "N");
    const bool through_contact = r.first_divergent_tick < 0 ||
                                 (first_contact >= 0 && r.first_divergent_tick > first_contact);
    v.require("agreed through the first contact tick", through_contact,
              "diverged " +
                  (r.first_divergent_tick < 0 ? std::string("never")
                                              : "at " + std::to_string(r.first_divergent_tick)) +
                  ", contact at " + std::to_string(first_contact));
  }
  j["recorded_pipeline"] = recorded;
  j["verdict"] = v.ok() ? "PASS" : "FAIL";
  j["failed_checks"] = v.failed();
  if (!o.json.empty()) write_json(o.json, j);
  v.finish();
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
