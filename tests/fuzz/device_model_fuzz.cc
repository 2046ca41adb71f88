// libFuzzer target: the Phantom device model file reader with its physical validation
// (reference/phantom/phantom_params.h).
#include "reference/phantom/phantom_params.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return dentsim::fuzz::run_reader(data, size, [](const std::string& bytes) {
    (void)dentsim::parse_phantom_params(bytes, "fuzz.json");
  });
}
