#include "sim/session_replay.h"

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>

#include "device/device.h"
#include "device/velocity_estimator.h"
#include "reference/core/io.h"
#include "sim/simulator.h"
#include "fast/registry.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {

ReplayResult replay_session(const Session& session, Pipeline& pipeline, ContactProvider& contacts,
                            const SixDofDeviceModel& model) {
  if (session.header.dof != model.dof()) {
    throw InputError("replay: the session has " + std::to_string(session.header.dof) +
                     " joints, the device model " + std::to_string(model.dof()));
  }
  ReplayResult r;
  if (session.records.empty()) return r;
  pipeline.reset(session.records.front().sample);
  double t_prev = session.records.front().sample.t;
  for (std::size_t k = 0; k < session.records.size(); ++k) {
    const SessionRecord& rec = session.records[k];
    const double T = k == 0 ? 1.0 / session.header.tick_rate_hz : rec.sample.t - t_prev;
    t_prev = rec.sample.t;
    const TickResult& out = pipeline.tick(rec.sample, T, contacts);
    const VecX d = out.tau - rec.tau;
    const double dt = d.cwiseAbs().maxCoeff();
    if (dt > r.max_torque_diff_n_m || !std::isfinite(dt)) {
      r.max_torque_diff_n_m = dt;
      r.worst_tick = static_cast<long>(k);
    }
    const Vec6 W = model.twist_to_joint(rec.sample.q).transpose() * d;
    const double df = W.head<3>().norm();
    r.max_force_diff_n = std::max(r.max_force_diff_n, df);
    if (r.first_divergent_tick < 0) {
      if (df > kReplayAgreementN || !std::isfinite(df)) {
        r.first_divergent_tick = static_cast<long>(k);
      } else {
        r.max_force_diff_before_divergence_n = std::max(r.max_force_diff_before_divergence_n, df);
      }
    }
    if (out.contacts.size() != rec.contacts) ++r.contact_count_mismatches;
    ++r.ticks;
  }
  return r;
}

PipelineConfig free_space_pipeline_config(const VecX& torque_limit) {
  PipelineConfig pc;
  pc.method = Method::kPmiVc;
  pc.torque_limit = torque_limit;
  DeviceCapabilities caps;  // a device reporting angles only, low-passed velocity (HDAPI)
  caps.measures_velocity = false;
  caps.velocity_lowpass_hz = VelocityEstimatorParams{}.cutoff_hz;
  pc.observer_input = matched_observer_input(caps);
  return pc;
}

ReplayResult replay_free_space_reference(const Session& session) {
  return replay_recorded_session(session, "reference");
}

ReplayResult replay_recorded_session(const Session& session, const std::string& pipeline,
                                     bool* scene_replayed) {
  if (find_stage_table(pipeline) == nullptr) {
    throw InputError("replay: unknown pipeline '" + pipeline + "' (expected one of " +
                     stage_table_names() + ")");
  }
  const nlohmann::json context =
      nlohmann::json::parse(session.header.context, nullptr, /*allow_exceptions=*/false);
  const bool has_scene = context.is_object() && context.contains("scene");
  if (scene_replayed != nullptr) *scene_replayed = has_scene;
  if (has_scene) {
    const Scene scene = parse_scene(context["scene"].dump(), "the recorded session's scene");
    SceneRigOptions o;
    o.pipeline = pipeline;
    const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, o);
    return replay_session(session, *rig->pipeline, *rig->contacts, *rig->model);
  }
  const PhantomParams params = default_phantom_params();
  const PhantomModel model(params);
  const std::unique_ptr<SixDofDeviceModel> belief = make_phantom_model(pipeline, params);
  const std::unique_ptr<Pipeline> p =
      make_pipeline(pipeline, *belief, free_space_pipeline_config(params.torque_limit_n_m));
  NoContacts contacts;
  return replay_session(session, *p, contacts, model);
}

nlohmann::json replay_report_json(const std::string& file, const std::string& pipeline,
                                  const Session& session, const ReplayResult& r,
                                  bool scene_replayed) {
  nlohmann::json j;
  j["file"] = file;
  j["pipeline"] = pipeline;
  j["context"] = session.header.context;
  j["environment"] =
      scene_replayed ? "the recorded scene (pipeline config, tooth, drilling)" : "free space";
  j["dof"] = session.header.dof;
  j["tick_rate_hz"] = session.header.tick_rate_hz;
  j["ticks"] = r.ticks;
  j["max_torque_diff_n_m"] = r.max_torque_diff_n_m;
  j["max_force_diff_n"] = r.max_force_diff_n;
  j["worst_tick"] = r.worst_tick;
  j["contact_count_mismatches"] = r.contact_count_mismatches;
  j["first_divergent_tick"] = r.first_divergent_tick;
  j["max_force_diff_before_divergence_n"] = r.max_force_diff_before_divergence_n;
  return j;
}

}  // namespace dentsim
