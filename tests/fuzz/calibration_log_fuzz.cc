// libFuzzer target: the calibration log reader of `dentsim calibrate` (calibration/log.h).
#include "calibration/log.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return dentsim::fuzz::run_reader(data, size, [](const std::string& bytes) {
    (void)dentsim::parse_calibration_log(bytes, "fuzz.csv");
  });
}
