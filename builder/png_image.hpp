// RgbImage and PNG files (libpng): the frames `shadowtiles render` writes.
// Errors: write_png → io_error (cannot create or write the file; the message names it),
// invalid_input for an image whose pixel buffer does not match its size. read_png → not_found,
// corrupt_data for a file that is not an 8-bit RGB PNG libpng can read. Safe on untrusted files
// (libpng validates; errors come back through its longjmp handler, never a crash).
// Thread safety: functions are reentrant.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles {

struct RgbImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3, row by row, row 0 at the top

  RgbImage() = default;
  RgbImage(uint32_t w, uint32_t h) : width(w), height(h), rgb(size_t(w) * h * 3, 0) {}
  void set(uint32_t x, uint32_t y, uint8_t r, uint8_t g, uint8_t b) {
    uint8_t* p = &rgb[(size_t(y) * width + x) * 3];
    p[0] = r;
    p[1] = g;
    p[2] = b;
  }
};

Status write_png(const std::filesystem::path& path, const RgbImage& image);
Result<RgbImage> read_png(const std::filesystem::path& path);

}  // namespace shadowtiles
