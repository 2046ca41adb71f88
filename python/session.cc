// Recorded sessions from Python (docs/hardware.md "Recorded sessions"): read a session written by
// `dentsim run --record FILE` (sim/session_record.h) as arrays, and replay it through a
// pipeline with `dentsim replay`'s library function (sim/session_replay.h
// replay_recorded_session), returning the numbers of `dentsim replay FILE --json OUT` (same keys).
#include "sim/session_record.h"
#include "sim/session_replay.h"
#include "python/module.h"

namespace dentsim::python {
namespace {

py::dict session_dict(const Session& s) {
  const auto n = static_cast<py::ssize_t>(s.records.size());
  const py::ssize_t dof = s.header.dof;
  py::array_t<std::uint64_t> tick(n);
  py::array_t<double> t(n);
  py::array_t<double> q({n, dof}), qd({n, dof}), tau({n, dof});
  py::array_t<std::uint32_t> contacts(n);
  auto wtick = tick.mutable_unchecked<1>();
  auto wt = t.mutable_unchecked<1>();
  auto wq = q.mutable_unchecked<2>();
  auto wqd = qd.mutable_unchecked<2>();
  auto wtau = tau.mutable_unchecked<2>();
  auto wc = contacts.mutable_unchecked<1>();
  for (py::ssize_t k = 0; k < n; ++k) {
    const SessionRecord& r = s.records[static_cast<std::size_t>(k)];
    wtick(k) = r.tick;
    wt(k) = r.sample.t;
    wc(k) = r.contacts;
    for (py::ssize_t j = 0; j < dof; ++j) {
      wq(k, j) = r.sample.q(j);
      wqd(k, j) = r.sample.qd(j);
      wtau(k, j) = r.tau(j);
    }
  }
  py::dict d;
  d["version"] = s.header.version;
  d["dof"] = s.header.dof;
  d["tick_rate_hz"] = s.header.tick_rate_hz;
  d["context"] = s.header.context;
  d["tick"] = tick;
  d["t"] = t;
  d["q"] = q;
  d["qd"] = qd;
  d["tau"] = tau;
  d["contacts"] = contacts;
  return d;
}

}  // namespace

void bind_session(py::module_& m) {
  m.def(
      "read_session",
      [](const py::handle& path) {
        return session_dict(read_session(path_arg(path, "read_session: path")));
      },
      py::arg("path"),
      "Read a recorded session (`dentsim run SCENE --record FILE`): version, dof, tick_rate_hz, "
      "context (the scene and pipeline as JSON text) and per tick: tick (uint64), t [s], q, qd "
      "(n, dof) [rad, rad/s], tau (n, dof) (the recorded command [N m]), contacts (uint32). A "
      "damaged file raises dentsim.InputError naming the record and its byte offset.");
  m.def(
      "replay",
      [](const py::handle& path_in, const std::string& pipeline) {
        const std::string path = path_arg(path_in, "replay: path");
        const Session session = read_session(path);
        bool scene = false;
        ReplayResult r;
        {
          py::gil_scoped_release release;
          r = replay_recorded_session(session, pipeline, &scene);
        }
        return json_to_py(replay_report_json(path, pipeline, session, r, scene));
      },
      py::arg("path"), py::arg("pipeline") = "reference",
      "Re-run a pipeline ('reference' or 'fast') open-loop on a recorded session and compare its "
      "torques with the recorded commands, as `dentsim replay FILE --pipeline P --json OUT`: a "
      "dict with the same keys (ticks, max_torque_diff_n_m, max_force_diff_n, "
      "first_divergent_tick, ...). A session recorded by `dentsim run` replays in its scene.");
}

}  // namespace dentsim::python
