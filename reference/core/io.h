// File output helpers: every file dentsim writes is written to a temporary beside the target and
// renamed into place, so a failed run never leaves a half-written or clobbered file.
#pragma once

#include <stdexcept>
#include <string>

namespace dentsim {

// An input error: bad file, bad value, bad flag. The message names what, where and what was
// expected. The CLI prints it on one line and exits with status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `contents` to `path` atomically (temp file + rename). Throws std::runtime_error naming
// the path on failure; the previous file, if any, is left untouched.
void write_file_atomic(const std::string& path, const std::string& contents);

// Reads a whole file; throws InputError naming the path if it cannot be read.
std::string read_file(const std::string& path);

}  // namespace dentsim
