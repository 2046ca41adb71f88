// dentsim.PhantomModel: the analytic model of the Phantom Premium 1.5/6DoF
// (reference/phantom/phantom_model.h, the specification the fast model is tested against), from
// the shipped default or a device model file (docs/phantom.md). Every method evaluates the C++
// model once; the arrays are copies.
#include <memory>
#include <optional>

#include "device/phantom_device.h"
#include "python/module.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::python {
namespace {

class PyPhantomModel {
 public:
  explicit PyPhantomModel(const py::object& path)
      : path_(path.is_none() ? std::string() : path_arg(path, "PhantomModel: path")),
        model_(path_.empty() ? default_phantom_params() : load_phantom_params(path_)) {}

  const PhantomModel& model() const { return model_; }
  const PhantomModelD& t() const { return model_.model(); }
  py::object path() const { return path_.empty() ? py::object(py::none()) : py::str(path_); }

  Vec6 q(const py::handle& v, const char* method) const {
    return vec6_arg(v, std::string("PhantomModel.") + method + ": q");
  }
  Vec6 qd(const py::handle& v, const char* method) const {
    return vec6_arg(v, std::string("PhantomModel.") + method + ": qd");
  }

 private:
  std::string path_;  // empty: the shipped default
  PhantomModel model_;
};

}  // namespace

void bind_model(py::module_& m) {
  py::class_<PyPhantomModel>(m, "PhantomModel", R"(The Phantom Premium 1.5/6DoF device model.

PhantomModel(path=None): the shipped default model, or the device model file at `path`
(docs/phantom.md; a bad file raises dentsim.InputError naming the file and the field).

Joint-space dynamics (thesis (2.1)): M(q) qdd + C(q, qd) qd + g(q) + tau_f(qd) = tau + f_h,
q = (q1..q6) [rad] as the device reports them (base yaw, upper arm, forearm, gimbal yaw, pitch,
roll), SI units. Vectors are array-likes of the model's dof (6) numbers; results are NumPy
float64 arrays.)")
      .def(py::init<const py::object&>(), py::arg("path") = py::none())
      .def_property_readonly(
          "dof", [](const PyPhantomModel& s) { return s.model().dof(); }, "Number of joints (6).")
      .def_property_readonly(
          "name", [](const PyPhantomModel& s) { return s.model().params().name; },
          "The model's name (the model file's `name`).")
      .def_property_readonly("path", &PyPhantomModel::path,
                             "The model file it was loaded from; None for the shipped default.")
      .def_property_readonly(
          "home_q",
          [](const PyPhantomModel& s) { return to_numpy(phantom_home_q(s.model().params())); },
          "The home configuration: the middle of the joint ranges [rad].")
      .def_property_readonly(
          "q_min", [](const PyPhantomModel& s) { return to_numpy(s.model().params().q_min_rad); },
          "Lower joint limits [rad].")
      .def_property_readonly(
          "q_max", [](const PyPhantomModel& s) { return to_numpy(s.model().params().q_max_rad); },
          "Upper joint limits [rad].")
      .def_property_readonly(
          "torque_limit",
          [](const PyPhantomModel& s) { return to_numpy(s.model().params().torque_limit_n_m); },
          "Motor torque limits [N m].")
      .def(
          "mass_matrix",
          [](const PyPhantomModel& s, const py::handle& q) {
            return to_numpy(s.t().M(s.q(q, "mass_matrix")));
          },
          py::arg("q"), "M(q), 6x6, symmetric positive definite, rotor armature included [kg m^2].")
      .def(
          "coriolis_matrix",
          [](const PyPhantomModel& s, const py::handle& q, const py::handle& qd) {
            return to_numpy(s.t().C(s.q(q, "coriolis_matrix"), s.qd(qd, "coriolis_matrix")));
          },
          py::arg("q"), py::arg("qd"), "C(q, qd), 6x6, the factorisation with dM/dt = C + C^T.")
      .def(
          "bias",
          [](const PyPhantomModel& s, const py::handle& q, const py::handle& qd) {
            return to_numpy(s.t().bias(s.q(q, "bias"), s.qd(qd, "bias")));
          },
          py::arg("q"), py::arg("qd"),
          "C(q, qd) qd: the Coriolis and centrifugal torques [N m], as the C++ model's bias() "
          "(gravity apart: gravity(q); friction apart: friction(qd)).")
      .def(
          "gravity",
          [](const PyPhantomModel& s, const py::handle& q) {
            return to_numpy(s.t().g(s.q(q, "gravity")));
          },
          py::arg("q"),
          "g(q): the generalised gravity force [N m], the gradient of potential_energy.")
      .def(
          "friction",
          [](const PyPhantomModel& s, const py::handle& qd) {
            return to_numpy(s.t().friction(s.qd(qd, "friction")));
          },
          py::arg("qd"), "tau_f(qd) = b qd + f_c tanh(qd / v_s) per joint [N m].")
      .def(
          "jacobian",
          [](const PyPhantomModel& s, const py::handle& q) {
            return to_numpy(s.t().tool_jacobian(s.q(q, "jacobian")));
          },
          py::arg("q"),
          "J_t(q), 6x6, the tool Jacobian of thesis (2.2): V1 = J_t qd with V1 = [v1; w1], v1 the "
          "tool tip's velocity in the world frame [m/s], w1 the angular velocity in the tool's "
          "own frame [rad/s].")
      .def(
          "forward_kinematics",
          [](const PyPhantomModel& s, const py::handle& q) {
            Vec3 x;
            Mat3 R;
            s.t().fk(s.q(q, "forward_kinematics"), &x, &R);
            return py::make_tuple(to_numpy(VecX(x)), to_numpy(MatX(R)));
          },
          py::arg("q"),
          "(x1, R1): the tool tip's position in the world frame [m] (z up, origin at the "
          "shoulder) and the tool's orientation (3x3 rotation, columns the tool axes in world).")
      .def(
          "potential_energy",
          [](const PyPhantomModel& s, const py::handle& q) {
            return s.t().potential_energy(s.q(q, "potential_energy"));
          },
          py::arg("q"), "sum_i m_i |g| z_i [J] (zero at z = 0).")
      .def(
          "kinetic_energy",
          [](const PyPhantomModel& s, const py::handle& q, const py::handle& qd) {
            return s.t().kinetic_energy(s.q(q, "kinetic_energy"), s.qd(qd, "kinetic_energy"));
          },
          py::arg("q"), py::arg("qd"), "1/2 qd^T M(q) qd [J].")
      .def(
          "forward_dynamics",
          [](const PyPhantomModel& s, const py::handle& q, const py::handle& qd,
             const py::handle& tau) {
            return to_numpy(
                s.t().forward_dynamics(s.q(q, "forward_dynamics"), s.qd(qd, "forward_dynamics"),
                                       vec6_arg(tau, "PhantomModel.forward_dynamics: tau")));
          },
          py::arg("q"), py::arg("qd"), py::arg("tau"),
          "qdd of M qdd + C qd + g + tau_f = tau [rad/s^2].")
      .def(
          "model_file",
          [](const PyPhantomModel& s) { return phantom_params_to_text(s.model().params()); },
          "The device model file of this model (JSON text; re-loads exactly).")
      .def("__repr__", [](const PyPhantomModel& s) {
        return "dentsim.PhantomModel(" +
               std::string(s.path().is_none() ? "" : "'" + s.path().cast<std::string>() + "'") +
               ")  # " + s.model().params().name;
      });
}

}  // namespace dentsim::python
