// libFuzzer target: the Wavefront OBJ reader with welding and manifold validation
// (tooth_io/mesh.h).
#include "tooth_io/mesh.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return dentsim::fuzz::run_reader(
      data, size, [](const std::string& bytes) { (void)dentsim::parse_obj(bytes, "fuzz.obj"); });
}
