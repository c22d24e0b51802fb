// In-memory PNG encoding (libpng) of 8-bit RGBA images: the server's rendered map tiles
// (/v1/render). The builder's own PNG files live in builder/png_image.* (builder and server never
// include each other).
// Errors: invalid_input for a pixel buffer that does not match its size; io_error if libpng fails.
// Thread safety: reentrant.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles::server {

struct RgbaImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> rgba;  // width * height * 4, row 0 at the top; zero = transparent

  RgbaImage() = default;
  RgbaImage(uint32_t w, uint32_t h) : width(w), height(h), rgba(size_t(w) * h * 4, 0) {}
  uint8_t* at(uint32_t x, uint32_t y) { return &rgba[(size_t(y) * width + x) * 4]; }
  const uint8_t* at(uint32_t x, uint32_t y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

// Fast settings (zlib level 1, one filter): a 256x256 tile encodes in well under a millisecond.
Result<std::string> encode_png(const RgbaImage& image);

}  // namespace shadowtiles::server
