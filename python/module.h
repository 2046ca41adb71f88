// The Python module `dentsim` (issue #20; docs/python.md): what its source files share.
//
// One file per area binds the library's own functions, so that Python computes nothing the C++
// does not (the pytest suite, tests/python/, checks the bindings against the `dentsim` command on
// the same inputs):
//   model.cc        PhantomModel: M(q), C, bias, gravity, Jacobian, kinematics (reference/phantom)
//   pipeline.cc     Pipeline: the tick of a registered implementation (fast/registry.h), tick by
//                   tick, in free space or in a scene's environment (sim/simulator.h's rig)
//   run.cc          run(scene): sim/simulator.h's run_scene, report.json's document
//                   (sim/run_report.h) and the time series as arrays; the built-in scenes
//   calibration.cc  calibration logs (calibration/log.h) and `dentsim calibrate`'s fit and report
//                   (calibration/calibrate.h)
//   session.cc      recorded sessions (sim/session_record.h) and their replay
//                   (sim/session_replay.h)
// Errors: InputError (reference/core/io.h: a bad file, value or name; the message names what and
// where) becomes dentsim.InputError, a subclass of ValueError; std::invalid_argument ValueError;
// other std::runtime_error RuntimeError.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>
#include <string>

#include "reference/core/types.h"

namespace dentsim::python {

namespace py = pybind11;

// A 1-D array-like of exactly n numbers (a list, a tuple, a NumPy array of any real dtype) as a
// vector. Throws InputError "<what>: expected n numbers, got ..." otherwise.
VecX vector_arg(const py::handle& v, int n, const std::string& what);
inline Vec6 vec6_arg(const py::handle& v, const std::string& what) {
  return Vec6(vector_arg(v, 6, what));
}

// A path argument: str or os.PathLike (os.fspath), as a string.
std::string path_arg(const py::handle& p, const std::string& what);

// A copy as a new float64 NumPy array: shape (n,) for a column vector (fixed-size or not),
// (rows, cols) for a matrix.
template <typename Derived>
py::array_t<double> to_numpy(const Eigen::MatrixBase<Derived>& m) {
  if constexpr (Derived::ColsAtCompileTime == 1) {
    py::array_t<double> a(static_cast<py::ssize_t>(m.size()));
    auto w = a.template mutable_unchecked<1>();
    for (Eigen::Index i = 0; i < m.size(); ++i) w(i) = m(i);
    return a;
  } else {
    py::array_t<double> a({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
    auto w = a.template mutable_unchecked<2>();
    for (Eigen::Index i = 0; i < m.rows(); ++i)
      for (Eigen::Index j = 0; j < m.cols(); ++j) w(i, j) = m(i, j);
    return a;
  }
}

// A JSON document as Python objects: null -> None, booleans, integers, floats, strings, arrays ->
// list, objects -> dict (so a report equals json.load of the file the CLI writes).
py::object json_to_py(const nlohmann::json& j);

void bind_model(py::module_& m);
void bind_pipeline(py::module_& m);
void bind_run(py::module_& m);
void bind_calibration(py::module_& m);
void bind_session(py::module_& m);

}  // namespace dentsim::python
