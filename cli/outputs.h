// The outputs of a command, checked before its work (issue #33, "work lost"): every command calls
// check_outputs once with every file (--json, --png, -o, --record) and every directory (--out) it
// will write, before it computes anything, so a long job never runs for minutes and then fails on
// its last step. A problem is an InputError naming the flag (exit status 2).
#pragma once

#include <string>
#include <vector>

#include "reference/core/io.h"

namespace dentsim::cli {

// Files: check_output_paths (reference/core/io.h): the directory exists and is writable, the path
// is not a directory, no two outputs share a file, no output is an input. Directories: an existing
// path must be a writable directory (not a file); a new one must be creatable, i.e. its nearest
// existing ancestor is a writable directory. Empty paths are skipped (an output not asked for).
void check_outputs(const std::vector<NamedPath>& files, const std::vector<NamedPath>& dirs = {},
                   const std::vector<NamedPath>& inputs = {});

// Creates the directory `dir.path` (and its parents) after check_outputs passed; throws
// InputError naming dir.what when it cannot.
void make_output_dir(const NamedPath& dir);

}  // namespace dentsim::cli
