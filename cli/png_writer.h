// PNG output for the CLI (the dentsim binary links libpng; reference/ stays free of it): encodes an
// RGB picture (tooth_io/render_png.h) as an 8-bit RGB PNG and writes it atomically.
#pragma once

#include <string>

#include "tooth_io/render_png.h"

namespace dentsim::cli {

// The PNG file's bytes. Throws std::runtime_error if libpng fails or the image is malformed.
std::string encode_png(const RgbImage& image);

// Encodes and writes `path` atomically (write_file_atomic); throws naming the path on failure.
void write_png(const std::string& path, const RgbImage& image);

}  // namespace dentsim::cli
