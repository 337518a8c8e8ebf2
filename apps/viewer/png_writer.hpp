// PNG files of the viewer's frames (libpng), written whole (temp file + rename).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace alloy::viewer {

/// An 8-bit RGBA picture, rows top to bottom.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  ///< width * height * 4
  const std::uint8_t* at(int x, int y) const { return &rgba[(std::size_t(y) * width + x) * 4]; }
};

/// Throws std::runtime_error naming the path.
void write_png(const std::filesystem::path& path, const Image& image);
/// Reads an RGBA (or RGB, converted) PNG; throws std::runtime_error.
Image read_png(const std::filesystem::path& path);

}  // namespace alloy::viewer
