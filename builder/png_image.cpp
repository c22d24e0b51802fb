#include "builder/png_image.hpp"

#include <csetjmp>
#include <cstdio>
#include <memory>

#include <png.h>

namespace shadowtiles {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// libpng reports errors by longjmp; keep its message for ours instead of printing it.
void on_png_error(png_structp png, png_const_charp message) {
  auto* text = static_cast<std::string*>(png_get_error_ptr(png));
  if (text) *text = message;
  png_longjmp(png, 1);
}
void on_png_warning(png_structp, png_const_charp) {}

}  // namespace

Status write_png(const std::filesystem::path& path, const RgbImage& image) {
  if (image.width == 0 || image.height == 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
    return make_error(ErrorCode::invalid_input, "image size does not match its pixels");
  File file(std::fopen(path.c_str(), "wb"));
  if (!file) return make_error(ErrorCode::io_error, "cannot create " + path.string());
  std::string message;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &message, on_png_error, on_png_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    return make_error(ErrorCode::io_error, "libpng cannot start writing");
  }
  std::vector<png_const_bytep> rows(image.height);
  for (uint32_t y = 0; y < image.height; ++y) rows[y] = &image.rgb[size_t(y) * image.width * 3];
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return make_error(ErrorCode::io_error, "writing " + path.string() + ": " + message);
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_rows(png, const_cast<png_bytepp>(rows.data()), image.height);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(file.get()) != 0 || std::ferror(file.get()))
    return make_error(ErrorCode::io_error, "writing " + path.string() + " failed");
  return {};
}

Result<RgbImage> read_png(const std::filesystem::path& path) {
  File file(std::fopen(path.c_str(), "rb"));
  if (!file) return make_error(ErrorCode::not_found, "cannot open " + path.string());
  std::string message;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &message, on_png_error, on_png_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, &info, nullptr);
    return make_error(ErrorCode::io_error, "libpng cannot start reading");
  }
  RgbImage image;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return make_error(ErrorCode::corrupt_data, path.string() + ": " + message);
  }
  png_init_io(png, file.get());
  png_set_user_limits(png, 1u << 15, 1u << 15);
  png_read_info(png, info);
  if (png_get_bit_depth(png, info) != 8 || png_get_color_type(png, info) != PNG_COLOR_TYPE_RGB) {
    png_destroy_read_struct(&png, &info, nullptr);
    return make_error(ErrorCode::corrupt_data, path.string() + ": not an 8-bit RGB PNG");
  }
  image = RgbImage(png_get_image_width(png, info), png_get_image_height(png, info));
  rows.resize(image.height);
  for (uint32_t y = 0; y < image.height; ++y) rows[y] = &image.rgb[size_t(y) * image.width * 3];
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

}  // namespace shadowtiles
