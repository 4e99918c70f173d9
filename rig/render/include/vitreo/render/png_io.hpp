#pragma once
// PNG files of rendered frames (libpng). Written atomically: to "<path>.tmp", then renamed, so a
// viewer or a test never reads half a file.
#include <string>

#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render {

/// Writes `image` (RGBA8, rows top to bottom) as an 8-bit RGBA PNG. Throws std::runtime_error.
void write_png(const std::string& path, const Image& image);
/// Reads any 8-bit PNG as RGBA8 (grey and RGB are expanded). Throws std::runtime_error.
Image read_png(const std::string& path);

}  // namespace vitreo::render
