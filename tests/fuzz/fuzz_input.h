// Shared body of the libFuzzer targets: run one reader on the fuzzer's bytes and accept only two
// outcomes, a parsed value or a dentsim::InputError (the CLI's exit status 2 with one message).
// Any other exception escapes and libFuzzer reports it as a crash; sanitizer findings abort.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "reference/core/io.h"

namespace dentsim::fuzz {

template <typename Reader>
int run_reader(const std::uint8_t* data, std::size_t size, Reader&& read) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    read(bytes);
  } catch (const InputError& e) {
    // The message must be printable: no raw control bytes of the input reach the terminal.
    for (const char c : std::string(e.what())) {
      const auto u = static_cast<unsigned char>(c);
      if (u < 0x20 || u == 0x7f) __builtin_trap();
    }
  }
  return 0;
}

}  // namespace dentsim::fuzz
