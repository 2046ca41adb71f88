// Refusing what cannot be stable (issue #32): the stability conditions the derivations state for
// each method, checked on a scene before it runs (`dentsim run`; `--force` runs it anyway, the
// supervisor of device/virtual_supervisor.h still watching).
//
// explicit (explicit-Euler proxy, standard coupling; docs/derivations/pmi_and_coupling.md §2):
// every force on the proxy is evaluated at t_k. For m x'' = -k x - b x' the explicit-Euler map has
// characteristic polynomial z^2 - (2 - bT/m) z + (1 - bT/m + kT^2/m); both roots lie inside the
// unit circle iff
//     k T < b                          (the determinant < 1: energy does not grow)        (E1)
//     2 b T < 4 m + k T^2              (the root at -1: the damper itself not overshooting) (E2)
// applied to
//   - the coupling alone (free space): k = k_vc, b = b_vc + proxy damping, m = proxy mass, and
//     k = k_vc,w, b = b_vc,w + proxy angular damping on the rotation (J for m) — the coupling's
//     bound in K T / b;
//   - the proxy in contact: k = k_vc + K_tooth (the contact's spring is explicit too: PMI's
//     midpoint term K T/2 is absent, reference/contact.h), b = b_vc + B_tooth + proxy damping.
// pmi / pmi-pd: the proxy's inertia, coupling, contact and friction are one implicit midpoint
// system (4.9): unconditionally stable for the linear elements, so there is no rate bound to
// check. The decomposition's conditions on M_d (diagonal at least the locked system's, D_d >= 0;
// docs/derivations/decomposition_and_observer.md §5) hold by construction: the tool preset is
// the device's locked inertia plus the instrument (sim/simulator.cc), and the observer's
// L T < 1 is checked when the scene is parsed.
#pragma once

#include <string>
#include <vector>

#include "sim/scene.h"

namespace dentsim {

// Every violated condition as "FIELD: message with the numbers and the bound" (empty: none).
std::vector<std::string> scene_stability_problems(const Scene& scene);

// Throws InputError "<origin>: FIELD: ... (run with --force to run it anyway)" naming the first
// violated condition.
void check_scene_stability(const Scene& scene);

}  // namespace dentsim
