// File input and output helpers shared by every reader and every command that writes files.
// - Every file dentsim writes is written to a temporary beside the target and renamed into
//   place, so a failed run never leaves a half-written or clobbered file (write_file_atomic).
// - Output paths are checked before any computation (check_output_paths): a missing directory,
//   an unwritable one, a path that is a directory, two outputs on one path, or an output that is
//   one of the inputs are input errors (exit status 2), so nothing is computed for nothing and no
//   input is ever overwritten.
// - Inputs are regular files of bounded size (read_file): /dev/zero, a FIFO or a directory is
//   refused instead of hanging or filling memory.
// - Text from a file quoted in a message goes through printable(): control bytes and non-ASCII
//   bytes are escaped (\xNN) and long text is cut, so an error never writes raw bytes to a
//   terminal.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace dentsim {

// An input error: bad file, bad value, bad flag. The message names what, where and what was
// expected. The CLI prints it on one line and exits with status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Largest input file read_file accepts [bytes]: 512 MiB (a binary STL of 10^7 triangles is
// 500 MB; docs/results/reliability.md states the limits).
inline constexpr std::size_t kMaxInputFileBytes = std::size_t{512} << 20;

// Writes `contents` to `path` atomically (temp file + rename). Throws std::runtime_error naming
// the path on failure; the previous file, if any, is left untouched.
void write_file_atomic(const std::string& path, const std::string& contents);

// Reads a whole regular file of at most `max_bytes`; throws InputError naming the path if it is
// missing, not a regular file (a directory, device, FIFO or socket), too large or unreadable.
std::string read_file(const std::string& path, std::size_t max_bytes = kMaxInputFileBytes);

// A path given on the command line or in a file, with the flag or field that named it.
struct NamedPath {
  std::string what;  // "--json", "-o", "LOG", "scene tooth.mesh", ...
  std::string path;
};

// Checks, before any work, that each output can be written and overwrites no input: its
// directory exists and is writable, the path is not a directory, no two outputs share a file and
// no output is (the same file as) an input. Empty paths are skipped. Throws InputError naming
// the flag(s) and path(s).
void check_output_paths(const std::vector<NamedPath>& outputs,
                        const std::vector<NamedPath>& inputs = {});

// `text` quoted for a message: printable ASCII kept, every other byte written as \xNN, cut to
// `max_chars` with "..." appended.
std::string printable(std::string_view text, std::size_t max_chars = 60);

}  // namespace dentsim
