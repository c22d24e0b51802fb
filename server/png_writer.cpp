#include "server/png_writer.hpp"

#include <csetjmp>

#include <png.h>

namespace shadowtiles::server {
namespace {

struct WriteState {
  std::string* out;
  std::string message;
};

// libpng reports errors by longjmp; keep its message for ours instead of printing it.
void on_error(png_structp png, png_const_charp message) {
  auto* state = static_cast<WriteState*>(png_get_error_ptr(png));
  if (state) state->message = message;
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}
void on_write(png_structp png, png_bytep data, png_size_t length) {
  auto* state = static_cast<WriteState*>(png_get_io_ptr(png));
  state->out->append(reinterpret_cast<const char*>(data), length);
}
void on_flush(png_structp) {}

}  // namespace

Result<std::string> encode_png(const RgbaImage& image) {
  if (image.width == 0 || image.height == 0 || image.rgba.size() != size_t(image.width) * image.height * 4)
    return make_error(ErrorCode::invalid_input, "image size does not match its pixels");
  std::string out;
  out.reserve(image.rgba.size() / 4);
  WriteState state{&out, {}};
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    return make_error(ErrorCode::io_error, "libpng cannot start writing");
  }
  std::vector<png_const_bytep> rows(image.height);
  for (uint32_t y = 0; y < image.height; ++y) rows[y] = image.at(0, y);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return make_error(ErrorCode::io_error, "encoding a PNG: " + state.message);
  }
  png_set_write_fn(png, &state, on_write, on_flush);
  png_set_compression_level(png, 1);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_rows(png, const_cast<png_bytepp>(rows.data()), image.height);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

}  // namespace shadowtiles::server
