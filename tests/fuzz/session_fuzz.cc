// libFuzzer target: the recorded-session reader of `dentsim replay` (sim/session_record.h) and
// what replay makes of a session's context: the JSON, and the scene in it through the scene
// reader (sim/scene.h) — the replay rebuilds that scene.
#include <nlohmann/json.hpp>

#include "sim/scene.h"
#include "sim/session_record.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return dentsim::fuzz::run_reader(data, size, [](const std::string& bytes) {
    const dentsim::Session s = dentsim::parse_session(bytes, "fuzz.rec");
    const nlohmann::json context =
        nlohmann::json::parse(s.header.context, nullptr, /*allow_exceptions=*/false);
    if (context.is_object() && context.contains("scene")) {
      (void)dentsim::parse_scene(context["scene"].dump(), "the recorded session's scene");
    }
  });
}
