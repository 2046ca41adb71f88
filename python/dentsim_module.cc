// The module's entry point and the conversions every area uses (python/module.h).
#include <cmath>

#include "python/module.h"
#include "reference/core/io.h"

#ifndef DENTSIM_VERSION
#error "DENTSIM_VERSION is set by python/CMakeLists.txt from the project's version"
#endif

namespace dentsim::python {

VecX vector_arg(const py::handle& v, int n, const std::string& what) {
  using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
  // ensure() converts any real array-like (and clears the Python error when it cannot); strings
  // and None are refused up front: NumPy would turn them into arrays of another shape.
  const auto not_numbers = [&] {
    return InputError(what + ": expected " + std::to_string(n) + " numbers, got " +
                      std::string(py::str(py::type::of(v).attr("__name__"))));
  };
  if (v.is_none() || py::isinstance<py::str>(v) || py::isinstance<py::bytes>(v)) {
    throw not_numbers();
  }
  const Array a = Array::ensure(v);
  if (!a) throw not_numbers();
  if (a.ndim() != 1 || a.shape(0) != n) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
      shape += (i ? ", " : "") + std::to_string(a.shape(i));
    shape += a.ndim() == 1 ? ",)" : ")";
    throw InputError(what + ": expected " + std::to_string(n) + " numbers (shape (" +
                     std::to_string(n) + ",)), got shape " + shape);
  }
  VecX out(n);
  for (int i = 0; i < n; ++i) out(i) = a.at(i);
  return out;
}

std::string path_arg(const py::handle& p, const std::string& what) {
  if (py::isinstance<py::str>(p)) return p.cast<std::string>();
  const py::object os = py::module_::import("os");
  if (py::isinstance(p, os.attr("PathLike"))) {
    const py::object s = os.attr("fspath")(p);
    if (py::isinstance<py::str>(s)) return s.cast<std::string>();
  }
  throw InputError(what + ": expected a str or os.PathLike path, got " +
                   std::string(py::str(py::type::of(p).attr("__name__"))));
}

py::object json_to_py(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null:
      return py::none();
    case nlohmann::json::value_t::boolean:
      return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer:
      return py::int_(j.get<std::int64_t>());
    case nlohmann::json::value_t::number_unsigned:
      return py::int_(j.get<std::uint64_t>());
    case nlohmann::json::value_t::number_float:
      return py::float_(j.get<double>());
    case nlohmann::json::value_t::string:
      return py::str(j.get_ref<const std::string&>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const nlohmann::json& e : j) l.append(json_to_py(e));
      return l;
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = json_to_py(it.value());
      return d;
    }
    default:  // binary and discarded values: no report holds them
      throw std::runtime_error("json_to_py: unsupported JSON value");
  }
}

}  // namespace dentsim::python

PYBIND11_MODULE(dentsim, m) {
  namespace dp = dentsim::python;
  m.doc() =
      "dentsim: stiff, stable haptic rendering for a dental simulator (docs/python.md).\n"
      "PhantomModel (the device model), Pipeline (the servo tick, tick by tick), run (a scene),\n"
      "calibration logs and fits, recorded sessions and their replay.";
  m.attr("__version__") = DENTSIM_VERSION;
  // InputError: a bad file, value or name, the C++ library's own message (what and where). A
  // ValueError, so callers that catch bad values catch it.
  pybind11::register_exception<dentsim::InputError>(m, "InputError", PyExc_ValueError);
  dp::bind_model(m);
  dp::bind_pipeline(m);
  dp::bind_run(m);
  dp::bind_calibration(m);
  dp::bind_session(m);
}
