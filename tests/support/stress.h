// Stress-test sizing. Suites named *Stress run in a short form by default (what CI runs) and in
// their long form when the environment sets DENTSIM_STRESS=full.
#pragma once

#include <cstdlib>
#include <string_view>

namespace dentsim::testing {

inline bool stress_full() {
  const char* v = std::getenv("DENTSIM_STRESS");
  return v != nullptr && std::string_view(v) == "full";
}

// `full` iterations in the long form, `short_form` otherwise.
inline long stress_count(long short_form, long full) { return stress_full() ? full : short_form; }

}  // namespace dentsim::testing
