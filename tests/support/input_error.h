// The message of the InputError that `f` throws ("(no InputError)" if it throws none), for tests
// that check what a bad-input message names.
#pragma once

#include <functional>
#include <string>

#include "reference/core/io.h"

namespace dentsim::testing {

inline std::string input_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

}  // namespace dentsim::testing
