// dentsim.Pipeline: the servo tick of one registered implementation (fast/registry.h:
// "reference", "fast"), driven tick by tick from Python like the loop owner drives it
// (device/closed_loop.h: reset on the first sample, then one tick per sample with the time to the
// next sample).
//
// Environment and configuration:
// - scene=None: free space (no contacts) with the configuration `dentsim replay` uses for a
//   session without a scene (free_space_pipeline_config, sim/session_replay.h: PMI + virtual
//   coupling, the model file's torque limits), on the default or the given device model;
// - scene=NAME|PATH: the scene's rig (sim/simulator.h build_scene_rig), the one `dentsim run`
//   and `dentsim replay` use: the scene's method, gains, tool and device model, and a fresh copy
//   of its tooth (contacts and drilling). Its simulated device and scripted hand are built but not
//   stepped: the samples come from Python.
// The tick itself is the C++ one (Pipeline::tick); only the arrays of its result are copies.
#include <memory>
#include <optional>

#include "device/phantom_device.h"
#include "sim/scene.h"
#include "sim/session_replay.h"
#include "sim/simulator.h"
#include "fast/phantom/phantom_model.h"
#include "fast/registry.h"
#include "python/module.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim::python {
namespace {

class PyPipeline {
 public:
  PyPipeline(const std::string& impl, const py::object& scene, const py::object& model) {
    if (find_stage_table(impl) == nullptr) {
      throw InputError("Pipeline: impl '" + impl + "': expected one of " + stage_table_names());
    }
    if (!scene.is_none()) {
      if (!model.is_none()) {
        throw InputError(
            "Pipeline: give either scene or model (a scene names its device model: "
            "device.model_file)");
      }
      const std::string name = path_arg(scene, "Pipeline: scene");
      SceneRigOptions o;
      o.pipeline = impl;
      o.device = "simulated-phantom";  // the samples come from Python, never from a device
      {
        py::gil_scoped_release release;  // voxelising the tooth takes a while
        const Scene s = load_scene(name);
        scene_name_ = s.name;
        rig_ = build_scene_rig(s, o);
      }
      pipeline_ = rig_->pipeline.get();
      env_ = rig_->contacts;
      tick_ = rig_->tick;
      home_q_ = rig_->q_home;
    } else {
      params_ = model.is_none() ? default_phantom_params()
                                : load_phantom_params(path_arg(model, "Pipeline: model"));
      own_model_ = make_phantom_model(impl, params_);
      own_pipeline_ =
          make_pipeline(impl, *own_model_, free_space_pipeline_config(params_.torque_limit_n_m));
      pipeline_ = own_pipeline_.get();
      env_ = &free_;
      home_q_ = phantom_home_q(params_);
    }
    sample_.q = VecX::Zero(6);
    sample_.qd = VecX::Zero(6);
  }

  const char* impl() const { return pipeline_->name(); }
  double tick_s() const { return tick_; }
  const VecX& home_q() const { return home_q_; }
  py::object scene() const {
    return rig_ ? py::object(py::str(scene_name_)) : py::object(py::none());
  }
  bool is_reset() const { return reset_; }

  std::string reset(const py::handle& q, const py::handle& qd, double t) {
    set_sample(q, qd, t, "reset");
    reset_ = true;
    return tick_status_name(pipeline_->reset(sample_));
  }

  py::dict tick(const py::handle& q, const py::handle& qd, double t, std::optional<double> T_arg) {
    set_sample(q, qd, t, "tick");
    const double T = T_arg.value_or(tick_);
    if (!reset_) {  // as the loop owner and `dentsim replay`: reset on the first sample
      pipeline_->reset(sample_);
      reset_ = true;
    }
    const TickResult& r = pipeline_->tick(sample_, T, *env_);
    py::dict d;
    d["status"] = tick_status_name(r.status);
    d["tau"] = to_numpy(r.tau);
    d["tau_gravity"] = to_numpy(r.tau_gravity);
    d["saturated"] = r.saturated;
    d["T1"] = to_numpy(VecX(r.T1));
    d["T1_vc"] = to_numpy(VecX(r.T1_vc));
    d["T1_pd"] = to_numpy(VecX(r.T1_pd));
    d["F1_hat"] = to_numpy(VecX(r.F1_hat));
    d["F_contact"] = to_numpy(VecX(r.F_contact));
    d["F_coupling"] = to_numpy(VecX(r.F_coupling));
    d["V1"] = to_numpy(VecX(r.V1));
    d["V_hat"] = to_numpy(VecX(r.V_hat));
    d["device_x"] = to_numpy(VecX(r.device.x));
    d["device_R"] = to_numpy(MatX(r.device.R));
    const ProxyState& p = pipeline_->proxy();
    d["proxy_x"] = to_numpy(VecX(p.pose.x));
    d["proxy_R"] = to_numpy(MatX(p.pose.R));
    d["contacts"] = r.contacts.size();
    d["max_depth"] = r.max_depth;
    d["friction_sliding"] = r.friction_sliding;
    d["grip_state"] = r.grip_state;
    d["removed_voxels"] = r.removed_voxels;
    // The wall-clock time of each stage inside C++ [ns] (what the tick costs without Python).
    py::dict ns;
    for (int i = 0; i < kStageCount; ++i) ns[tick_stage_name(i)] = r.stage_ns[i];
    d["stage_ns"] = ns;
    return d;
  }

  py::dict proxy() const {
    const ProxyState& p = pipeline_->proxy();
    py::dict d;
    d["x"] = to_numpy(VecX(p.pose.x));
    d["R"] = to_numpy(MatX(p.pose.R));
    d["V"] = to_numpy(VecX(p.V));
    return d;
  }

 private:
  void set_sample(const py::handle& q, const py::handle& qd, double t, const char* method) {
    sample_.q = vector_arg(q, 6, std::string("Pipeline.") + method + ": q");
    sample_.qd = qd.is_none() ? VecX(VecX::Zero(6))
                              : vector_arg(qd, 6, std::string("Pipeline.") + method + ": qd");
    sample_.t = t;
  }

  // Scene: the rig owns the models, the pipeline and the environment.
  std::unique_ptr<SceneRig> rig_;
  std::string scene_name_;
  // Free space: owned here.
  PhantomParams params_;
  std::unique_ptr<SixDofDeviceModel> own_model_;  // the implementation's (fast/registry.h)
  std::unique_ptr<Pipeline> own_pipeline_;
  NoContacts free_;

  Pipeline* pipeline_ = nullptr;
  ContactProvider* env_ = nullptr;
  double tick_ = 1e-3;  // free space: the Phantom's 1 kHz servo rate
  VecX home_q_;
  DeviceSample sample_;
  bool reset_ = false;
};

}  // namespace

void bind_pipeline(py::module_& m) {
  py::class_<PyPipeline>(m, "Pipeline", R"(The servo tick of one implementation, tick by tick.

Pipeline(impl="fast", scene=None, model=None)
  impl   "fast" or "reference" (the registry of fast/registry.h; `dentsim run --pipeline`)
  scene  None: free space with the free-space configuration of `dentsim replay` (PMI + virtual
         coupling) on the device model `model` (a model file path; None: the shipped default).
         A built-in scene name or a scene file: the scene's method, gains, device model and a
         fresh copy of its tooth, exactly as `dentsim run` and `dentsim replay` build them.

reset(q, qd=None, t=0.0) places the proxy on the device pose at rest; tick(q, qd, t, T=None)
runs one tick on the device sample (q [rad], qd [rad/s], t [s]) for a tick of length T [s]
(None: 1/tick_hz of the scene, 1 ms in free space) and returns the tick's result as a dict of
NumPy arrays: tau (joint torques sent to the device [N m]), T1 (wrench on the device, f world
[N], tau body [N m]), F_contact, F_coupling (wrenches on the proxy), F1_hat (the observer's
estimate of the hand's wrench), V1, V_hat (twists), device_x/device_R, proxy_x/proxy_R, the
contact count, status ("ok" or the fault's name; a failed tick commands zero torque), stage_ns
(each stage's wall-clock time inside C++ [ns]). A tick before any reset() resets on its sample
first, as the loop owner does.)")
      .def(py::init<const std::string&, const py::object&, const py::object&>(),
           py::arg("impl") = "fast", py::arg("scene") = py::none(), py::arg("model") = py::none())
      .def_property_readonly("impl", &PyPipeline::impl,
                             "The implementation: 'fast' or 'reference'.")
      .def_property_readonly("scene", &PyPipeline::scene, "The scene's name; None in free space.")
      .def_property_readonly("tick_s", &PyPipeline::tick_s,
                             "The nominal tick length T = 1/tick_hz [s] (tick's default).")
      .def_property_readonly(
          "home_q", [](const PyPipeline& p) { return to_numpy(p.home_q()); },
          "The device's home configuration [rad] (the scene starts there; its tooth is placed "
          "relative to the tool tip at home).")
      .def_property_readonly("is_reset", &PyPipeline::is_reset,
                             "Whether reset() (or a first tick) has run.")
      .def("reset", &PyPipeline::reset, py::arg("q"), py::arg("qd") = py::none(),
           py::arg("t") = 0.0, "Proxy on the device pose at rest, observers at rest; the status.")
      .def("tick", &PyPipeline::tick, py::arg("q"), py::arg("qd") = py::none(), py::arg("t") = 0.0,
           py::arg("T") = py::none(), "One tick; its result as a dict.")
      .def("proxy", &PyPipeline::proxy, "The proxy's state: x, R, V (twist).")
      .def("__repr__", [](const PyPipeline& p) {
        return std::string("dentsim.Pipeline(impl='") + p.impl() + "'" +
               (p.scene().is_none() ? "" : ", scene='" + p.scene().cast<std::string>() + "'") + ")";
      });
}

}  // namespace dentsim::python
