#include "reference/tools.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "reference/core/io.h"

namespace dentsim {
namespace {

// The instrument table (sources and reasoning in tools.h).
const std::array<ToolInstrument, 3>& instruments() {
  static const std::array<ToolInstrument, 3> table = {{
      {"explorer", 0.010, 0.170, 0.085, 0.2, 2e-4},
      {"scaler", 0.015, 0.170, 0.085, 0.3, 3e-4},
      {"handpiece", 0.065, 0.100, 0.050, 1.0, 1e-3},
  }};
  return table;
}

std::string joined_names() {
  std::string s;
  for (const auto& t : instruments()) s += (s.empty() ? "" : ", ") + t.name;
  return s;
}

}  // namespace

Mat6 tool_inertia_floor() { return block_diag(0.19 * Mat3::Identity(), 1.2e-4 * Mat3::Identity()); }

ToolInstrument tool_instrument(const std::string& name) {
  for (const auto& t : instruments()) {
    if (t.name == name) return t;
  }
  throw InputError("unknown tool '" + name + "' (expected one of: " + joined_names() + ")");
}

std::vector<std::string> tool_preset_names() {
  std::vector<std::string> names;
  for (const auto& t : instruments()) names.push_back(t.name);
  return names;
}

ToolDynamics tool_preset(const std::string& name, const Mat6& floor) {
  const ToolInstrument inst = tool_instrument(name);
  const Vec6 diag = floor.diagonal();
  if (!diag.allFinite() || diag.minCoeff() < 0.0) {
    throw std::invalid_argument(
        "tool_preset: the inertia floor must have a finite, non-negative "
        "diagonal");
  }
  const double m = diag.head<3>().maxCoeff() + inst.mass;       // [kg]
  const double J = diag.tail<3>().maxCoeff() + inst.inertia();  // [kg m^2]
  ToolDynamics tool;
  tool.name = inst.name;
  tool.M_d = block_diag(m * Mat3::Identity(), J * Mat3::Identity());
  tool.D_d = block_diag(inst.damping_lin * Mat3::Identity(), inst.damping_ang * Mat3::Identity());
  return tool;
}

ToolDynamics tool_preset(const std::string& name) {
  return tool_preset(name, tool_inertia_floor());
}

bool meets_inertia_floor(const ToolDynamics& tool, const Mat6& M_L) {
  return (tool.M_d.diagonal() - M_L.diagonal()).minCoeff() >= 0.0;
}

}  // namespace dentsim
