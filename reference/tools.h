// Tool presets: the desired locked-system dynamics M_d dv_L/dt + D_d v_L = F_L of each virtual
// dental instrument (thesis §3.1.2, "dynamics augmentation control"), used by the passive
// decomposition feed-forward (4.7) in reference/decomposition.h.
//
// Units and frames: M_d = diag(m I3 [kg], J I3 [kg m^2]), D_d = diag(b_x I3 [N s/m],
// b_w I3 [N m s/rad]) acting on the locked twist v_L = [v (world); w (device tip frame)], the
// tool's reference point being its working tip (as for the proxy, thesis §2.1.2).
//
// How the numbers are made (docs/derivations/decomposition_and_observer.md, "Tool presets"):
//     M_d = inertia floor + instrument inertia,   D_d = instrument damping.
// - The floor: the thesis (§3.1.2) requires the diagonal of M_d to be similar to or larger than
//   that of the device; the locked system being rendered also carries the proxy, so the floor is
//   the locked inertia M_L = M1 + E^T M2 E. A passive device cannot feel lighter than its own
//   apparent inertia, so a virtual instrument is rendered as the device plus the instrument.
//   Nominal floor (tool_inertia_floor()): 0.19 kg = Phantom Premium 1.5/6DoF apparent tip mass
//   (manufacturer figure < 75 g for the 3-DoF Premium 1.5, up to ~136 g quoted for the 6-DoF /
//   high-force variants; the larger value is used) + the default proxy mass 0.05 kg, rounded
//   up; rotational 1.2e-4 kg m^2 = a stylus/gimbal of ~0.1 kg at ~3 cm from the tip (1e-4)
//   + the default proxy inertia 2e-5. A calibrated device should pass its own M_L to the
//   two-argument tool_preset().
// - The instruments (mass of real hand instruments; rotational inertia about the working tip of
//   a slender body of length L with the centre of mass at distance c: m (c^2 + L^2/12)):
//     explorer probe  m = 10 g (hollow-handle explorer, 10-15 g), L = 170 mm, c = 85 mm
//     scaler          m = 15 g (hand scaler, 10-20 g),             L = 170 mm, c = 85 mm
//     handpiece       m = 65 g (high-speed handpiece, 50-80 g),    L = 100 mm, c = 50 mm
//   The rotational inertia is taken isotropic (the largest, transverse value): the core does not
//   fix a tool axis in the body frame, and a centre of mass off the tip would make M_d depend on
//   the pose (the thesis's C_L,d), which (4.7) drops.
// - D_d is small (it is felt as free-space drag, and D_d >= 0 keeps the locked system passive:
//   dV/dt = -v_L^T D_d v_L + v_L^T F_L): 0.2 / 0.3 N s/m for the hand instruments, 1.0 N s/m for
//   the handpiece (its hose and its "more resistant" feel, thesis §3.1.2).
#pragma once

#include <string>
#include <vector>

#include "reference/core/params.h"

namespace dentsim {

// The instrument part of a preset (added to the inertia floor).
struct ToolInstrument {
  std::string name;
  double mass = 0.0;          // m [kg]
  double length = 0.0;        // L [m]
  double com_distance = 0.0;  // c [m], centre of mass from the working tip
  double damping_lin = 0.0;   // b_x [N s/m]
  double damping_ang = 0.0;   // b_w [N m s/rad]
  double inertia() const { return mass * (com_distance * com_distance + length * length / 12.0); }
};

// The nominal locked-system inertia floor diag(0.19 I, 1.2e-4 I) described above.
Mat6 tool_inertia_floor();

// The preset `name` on the nominal floor: "explorer", "scaler", "handpiece". Throws InputError
// naming the value and the accepted names otherwise.
ToolDynamics tool_preset(const std::string& name);
// The preset `name` on a given floor (e.g. the calibrated device's M_L): M_d's translational
// (rotational) diagonal is the largest translational (rotational) diagonal entry of `floor` plus
// the instrument's mass (inertia). Throws InputError for an unknown name, std::invalid_argument
// for a floor with non-finite or negative diagonal.
ToolDynamics tool_preset(const std::string& name, const Mat6& floor);
std::vector<std::string> tool_preset_names();
// The instrument table entry (throws InputError for an unknown name).
ToolInstrument tool_instrument(const std::string& name);

// True when every diagonal entry of M_d is at least the corresponding one of M_L (thesis §3.1.2).
bool meets_inertia_floor(const ToolDynamics& tool, const Mat6& M_L);

}  // namespace dentsim
