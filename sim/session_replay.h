// Open-loop replay of a recorded session (sim/session_record.h) through a Pipeline: the
// differential test of issue #15 on data recorded from hardware (`dentsim replay`).
//
// The pipeline is reset on the first recorded sample and ticked on every recorded sample in order
// with the tick length the live loop used (device/closed_loop.h): T_0 = 1 / tick_rate_hz,
// T_k = t_k - t_k-1. Its torque tau'_k is compared with the recorded command tau_k:
//   max_torque_diff_n_m = max_k max_i |tau'_k,i - tau_k,i|                        [N m]
//   max_force_diff_n    = max_k |f| of J1(q_k)^T (tau'_k - tau_k)  (the force part of the device
//                         wrench the difference makes, tau = J1^-T T; reference/tick.h)   [N]
// Replaying with the recording's own pipeline and environment reproduces it bit for bit; another
// pipeline (fast vs reference) gives their difference on the same inputs.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "sim/session_record.h"
#include "reference/core/contact_provider.h"
#include "reference/tick.h"

namespace dentsim {

struct ReplayResult {
  long ticks = 0;
  double max_torque_diff_n_m = 0.0;
  double max_force_diff_n = 0.0;
  long worst_tick = -1;               // index of the record with the largest torque difference
  long contact_count_mismatches = 0;  // ticks whose contact count differs from the recording
  // The first record whose force difference exceeds kReplayAgreementN (-1: none): before it the
  // replay agrees with the recording to round-off; a discrete event (a voxel removed one tick
  // apart) makes them part there (docs/results/fast_crosscheck.md).
  long first_divergent_tick = -1;
  double max_force_diff_before_divergence_n = 0.0;
};

inline constexpr double kReplayAgreementN = 1e-9;  // [N] (docs/tolerance_policy.md item 9)

// Throws InputError if the session's dof is not the model's.
ReplayResult replay_session(const Session& session, Pipeline& pipeline, ContactProvider& contacts,
                            const SixDofDeviceModel& model);

// The pipeline configuration of a free-space run on the Phantom (`dentsim replay` without a
// scene; the one tests record with): PMI + virtual coupling, the model file's torque limits, the
// observer input matched to a device without a tachometer.
PipelineConfig free_space_pipeline_config(const VecX& torque_limit);

// replay_session() through the reference pipeline with free_space_pipeline_config() on the
// default Phantom model (default_phantom_params()), no contacts.
ReplayResult replay_free_space_reference(const Session& session);

// `dentsim replay`: a session whose context holds a scene (`dentsim run ... --record`: {"scene":
// the scene's JSON, "pipeline": ...}) is replayed through that scene's pipeline configuration and
// a fresh copy of its tooth (contacts and drilling as in the run), with the implementation
// `pipeline` ("reference", "fast"); any other session in free space as
// replay_free_space_reference, with that implementation. `scene_replayed` (optional) says which.
// Throws InputError for an unknown pipeline or a context scene that does not parse.
ReplayResult replay_recorded_session(const Session& session, const std::string& pipeline,
                                     bool* scene_replayed = nullptr);

// The numbers of `dentsim replay FILE --pipeline P --json OUT` (and of the Python module's
// dentsim.replay): the session `file` replayed through `pipeline`, `scene_replayed` as returned by
// replay_recorded_session.
nlohmann::json replay_report_json(const std::string& file, const std::string& pipeline,
                                  const Session& session, const ReplayResult& r,
                                  bool scene_replayed);

}  // namespace dentsim
