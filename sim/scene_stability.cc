#include "sim/scene_stability.h"

#include <cstdio>

#include "reference/core/io.h"

namespace dentsim {

namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

// (E1) and (E2) of scene_stability.h for one explicit-Euler element; appends the failures.
void explicit_bounds(const std::string& k_field, const std::string& b_field, double k, double b,
                     double m, double T, const std::string& k_unit, const std::string& b_unit,
                     const std::string& what, std::vector<std::string>* out) {
  if (!(k * T < b)) {
    out->push_back(k_field + ": explicit Euler is stable only for K T < b (" + what + "): K T = " +
                   num(k) + " " + k_unit + " x " + num(T * 1e3) + " ms = " + num(k * T) + " " +
                   b_unit + ", b = " + num(b) + " " + b_unit +
                   "; lower the stiffness, add damping, raise tick_hz, or use pmi / pmi-pd");
  }
  if (!(2.0 * b * T < 4.0 * m + k * T * T)) {
    out->push_back(b_field + ": explicit Euler is stable only for 2 b T < 4 m + K T^2 (" + what +
                   "): 2 b T = " + num(2.0 * b * T) + ", 4 m + K T^2 = " +
                   num(4.0 * m + k * T * T) + "; lower the damping or raise tick_hz");
  }
}

}  // namespace

std::vector<std::string> scene_stability_problems(const Scene& s) {
  std::vector<std::string> out;
  const double T = 1.0 / s.tick_hz;
  const SceneMethod& m = s.method;
  if (m.method == Method::kExplicitVc) {
    const double b_lin = m.coupling.b_lin + m.proxy.damping_lin;
    const double b_ang = m.coupling.b_ang + m.proxy.damping_ang;
    const double J = m.proxy.inertia.diagonal().minCoeff();
    explicit_bounds("method.k_vc_n_per_m", "method.b_vc_n_s_per_m", m.coupling.k_lin, b_lin,
                    m.proxy.mass, T, "N/m", "N s/m",
                    "the coupling: b = b_vc_n_s_per_m + proxy.damping_n_s_per_m", &out);
    explicit_bounds("method.k_vc_ang_n_m_per_rad", "method.b_vc_ang_n_m_s_per_rad",
                    m.coupling.k_ang, b_ang, J, T, "N m/rad", "N m s/rad",
                    "the coupling's rotation: b = b_vc_ang + proxy.damping_ang", &out);
    explicit_bounds("tooth.k_tooth_n_per_m", "tooth.b_tooth_n_s_per_m",
                    m.coupling.k_lin + s.tooth.k_tooth, b_lin + s.tooth.b_tooth, m.proxy.mass, T,
                    "N/m", "N s/m",
                    "the proxy in contact: K = k_vc + k_tooth, b = b_vc + b_tooth + proxy damping",
                    &out);
  }
  return out;
}

void check_scene_stability(const Scene& scene) {
  const std::vector<std::string> p = scene_stability_problems(scene);
  if (!p.empty()) {
    throw InputError(scene.origin + ": " + p.front() +
                     " (the run cannot be stable; `dentsim run --force` runs it anyway)");
  }
}

}  // namespace dentsim
