// The decision both twins of add_anchored_spring_unchecked (reference/contact.h, fast/contact.h)
// share (issue #32): the across-normal stiffness the explicit treatment carries, 2 b_t / T, or -1
// when nothing is to be added (kExplicit, or a free anchor h = 0). Never throws or allocates.
#pragma once

#include "reference/contact.h"

namespace dentsim {

double anchored_spring_explicit_stiffness(const AnchoredSpring& spring, double T, Scheme scheme,
                                          double b_lin, double b_ang);

}  // namespace dentsim
