// Raw tile payload (method `raw`): the tile's lower-bound depth map as float32, the reference every
// compressed method is measured against.
// FORMAT (little-endian): u32 tile size T, then T*T float32 row-major (texel (u, v) at v*T + u).
// Parsing checks the size against the payload length: safe on untrusted input.
// Thread safety: RawTileView is immutable after parse.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles {

std::vector<uint8_t> encode_raw_tile(uint32_t size, std::span<const float> lower);

class RawTileView {
 public:
  static Result<RawTileView> parse(std::span<const uint8_t> payload);
  uint32_t size() const { return size_; }
  float value(uint32_t u, uint32_t v) const { return values_[size_t(v) * size_ + u]; }
  size_t memory_bytes() const { return values_.size() * sizeof(float); }

 private:
  uint32_t size_ = 0;
  std::vector<float> values_;
};

}  // namespace shadowtiles
