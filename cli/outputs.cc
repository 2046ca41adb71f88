#include "cli/outputs.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace dentsim::cli {

namespace fs = std::filesystem;

namespace {

void check_output_dir(const NamedPath& d) {
  const std::string where = d.what + " '" + d.path + "'";
  std::error_code ec;
  const fs::path p(d.path);
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec)) {
      throw InputError(where + ": exists and is not a directory; expected a directory");
    }
    if (::access(p.c_str(), W_OK) != 0) {
      throw InputError(where + ": the directory is not writable (" + std::strerror(errno) + ")");
    }
    return;
  }
  // A new directory: its nearest existing ancestor must be a directory we may write into.
  fs::path up = fs::absolute(p, ec).parent_path();
  while (!up.empty() && !fs::exists(up, ec) && up != up.root_path()) up = up.parent_path();
  if (!fs::is_directory(up, ec)) {
    throw InputError(where + ": cannot create the directory: '" + up.string() +
                     "' is not a directory");
  }
  if (::access(up.c_str(), W_OK) != 0) {
    throw InputError(where + ": cannot create the directory: '" + up.string() +
                     "' is not writable (" + std::strerror(errno) + ")");
  }
}

}  // namespace

void check_outputs(const std::vector<NamedPath>& files, const std::vector<NamedPath>& dirs,
                   const std::vector<NamedPath>& inputs) {
  for (const NamedPath& d : dirs) {
    if (!d.path.empty()) check_output_dir(d);
  }
  check_output_paths(files, inputs);
}

void make_output_dir(const NamedPath& dir) {
  std::error_code ec;
  fs::create_directories(dir.path, ec);
  if (ec || !fs::is_directory(dir.path)) {
    throw InputError(dir.what + " '" + dir.path + "': cannot create the directory (" +
                     (ec ? ec.message() : std::string("not a directory")) + ")");
  }
}

}  // namespace dentsim::cli
