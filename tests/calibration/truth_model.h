// The perturbed device the calibration end-to-end tests (and the docs' commands, through
// tests/calibration/data/perturbed_phantom.json) calibrate: the defaults with the arm's
// masses/inertias +-20 %, damping x3 and Coulomb friction x1.5, so that the defaults are wrong in
// gravity by ~28 % and in damping by x3.
#pragma once

#include "reference/phantom/phantom_params.h"

namespace dentsim::testing {

inline PhantomParams calibration_truth_model() {
  PhantomParams p = default_phantom_params();
  p.name = "perturbed test device";
  p.upper_arm.mass_kg *= 1.2;
  p.upper_arm.inertia_kg_m2 *= 1.2;
  p.forearm.mass_kg *= 0.8;
  p.forearm.inertia_kg_m2 *= 0.8;
  p.damping_n_m_s_per_rad *= 3.0;
  p.coulomb_n_m *= 1.5;
  return p;
}

}  // namespace dentsim::testing
