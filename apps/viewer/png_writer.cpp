#include "apps/viewer/png_writer.hpp"

#include <png.h>

#include <stdexcept>
#include <string>

#include "apps/viewer/scene_writer.hpp"

namespace alloy::viewer {

void write_png(const std::filesystem::path& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != std::size_t(image.width) * image.height * 4)
    throw std::runtime_error("cannot write '" + path.string() + "': empty picture");
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  img.width = png_uint_32(image.width);
  img.height = png_uint_32(image.height);
  img.format = PNG_FORMAT_RGBA;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&img, nullptr, &size, 0, image.rgba.data(), 0, nullptr))
    throw std::runtime_error("cannot encode '" + path.string() + "': " + img.message);
  std::string data(size, '\0');
  if (!png_image_write_to_memory(&img, data.data(), &size, 0, image.rgba.data(), 0, nullptr))
    throw std::runtime_error("cannot encode '" + path.string() + "': " + img.message);
  data.resize(size);
  write_file_whole(path, data);
}

Image read_png(const std::filesystem::path& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str()))
    throw std::runtime_error("cannot read '" + path.string() + "': " + img.message);
  img.format = PNG_FORMAT_RGBA;
  Image out;
  out.width = int(img.width);
  out.height = int(img.height);
  out.rgba.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.rgba.data(), 0, nullptr)) {
    png_image_free(&img);
    throw std::runtime_error("cannot read '" + path.string() + "': " + img.message);
  }
  return out;
}

}  // namespace alloy::viewer
