#include "reference/core/io.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace dentsim {

namespace fs = std::filesystem;

void write_file_atomic(const std::string& path, const std::string& contents) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
    }
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error("cannot write '" + path + "': write failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string err = std::strerror(errno);
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': " + err);
  }
}

std::string read_file(const std::string& path, std::size_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw InputError("cannot read '" + path + "': " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                       : S_ISFIFO(st.st_mode) ? "a FIFO"
                       : S_ISCHR(st.st_mode)  ? "a character device"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    throw InputError("cannot read '" + path + "': it is " + kind + "; expected a regular file");
  }
  if (static_cast<std::size_t>(st.st_size) > max_bytes) {
    throw InputError("cannot read '" + path + "': " + std::to_string(st.st_size) +
                     " bytes, more than the limit of " + std::to_string(max_bytes) + " bytes");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot read '" + path + "': " + std::strerror(errno));
  std::string out(static_cast<std::size_t>(st.st_size), '\0');
  in.read(out.data(), static_cast<std::streamsize>(out.size()));
  if (in.gcount() != static_cast<std::streamsize>(out.size())) {
    throw InputError("cannot read '" + path + "': the file changed size while it was read");
  }
  return out;
}

namespace {

// Two paths name the same file: equivalent() when both exist, else equal normalised paths.
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ea, eb;
  if (fs::exists(a, ea) && fs::exists(b, eb)) {
    std::error_code e;
    const bool eq = fs::equivalent(a, b, e);
    if (!e) return eq;
  }
  return fs::weakly_canonical(a, ea) == fs::weakly_canonical(b, eb);
}

}  // namespace

void check_output_paths(const std::vector<NamedPath>& outputs,
                        const std::vector<NamedPath>& inputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& o = outputs[i];
    if (o.path.empty()) continue;
    const std::string where = o.what + " '" + o.path + "'";
    std::error_code ec;
    if (fs::is_directory(o.path, ec)) {
      throw InputError(where + ": is a directory; expected a file path");
    }
    fs::path dir = fs::path(o.path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec)) {
      throw InputError(where + ": directory '" + dir.string() + "' does not exist");
    }
    if (::access(dir.c_str(), W_OK) != 0) {
      throw InputError(where + ": directory '" + dir.string() + "' is not writable (" +
                       std::strerror(errno) + ")");
    }
    if (fs::exists(o.path, ec) && ::access(o.path.c_str(), W_OK) != 0) {
      throw InputError(where + ": exists and is not writable (" + std::strerror(errno) + ")");
    }
    for (const NamedPath& in : inputs) {
      if (!in.path.empty() && same_file(o.path, in.path)) {
        throw InputError(where + ": is the input " + in.what + " '" + in.path +
                         "'; refusing to overwrite an input");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (!outputs[j].path.empty() && same_file(o.path, outputs[j].path)) {
        throw InputError(where + ": is also the output " + outputs[j].what +
                         "; each output needs its own file");
      }
    }
  }
}

std::string printable(std::string_view text, std::size_t max_chars) {
  std::string out;
  for (const char c : text) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      out += c;
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    }
  }
  return out;
}

}  // namespace dentsim
