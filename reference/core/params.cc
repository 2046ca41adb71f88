#include "reference/core/params.h"

#include <stdexcept>

namespace dentsim {

const char* method_name(Method m) {
  switch (m) {
    case Method::kExplicitVc: return "explicit";
    case Method::kPmiVc: return "pmi";
    case Method::kPmiPd: return "pmi-pd";
  }
  return "?";
}

Method parse_method(const std::string& s) {
  if (s == "explicit") return Method::kExplicitVc;
  if (s == "pmi") return Method::kPmiVc;
  if (s == "pmi-pd") return Method::kPmiPd;
  throw std::invalid_argument("unknown method '" + s + "' (expected explicit, pmi or pmi-pd)");
}

}  // namespace dentsim
