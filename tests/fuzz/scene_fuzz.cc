// libFuzzer target: the scene file reader of `dentsim run` (sim/scene.h) and its JSON reader
// (reference/core/json_reader.h).
#include "sim/scene.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return dentsim::fuzz::run_reader(
      data, size, [](const std::string& bytes) { (void)dentsim::parse_scene(bytes, "fuzz.json"); });
}
