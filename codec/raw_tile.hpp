// Raw tile payload (method `raw`): the tile's lower-bound depth map as float32, the reference every
// compressed method is measured against.
// FORMAT (little-endian), version 1, a 12-byte header then the texels:
//   offset  0  magic "STRW"             4 bytes
//   offset  4  format_version           u16 (kRawTileFormatVersion)
//   offset  6  reserved                 u16, 0
//   offset  8  tile size T              u32, a power of two <= 16384
//   offset 12  T*T float32 row-major (texel (u, v) at v*T + u), every value finite
// Payloads written before the header (version 0: u32 T, then the texels) are still read: their
// first word is a power of two, which the magic never is.
// Parsing checks magic, version, reserved bits, size against the payload length and that every
// value is finite (the builder stores lower bounds of normalised depth; misses are 1, never inf):
// corrupt_data otherwise, unsupported for a newer version. Safe on untrusted input.
// Thread safety: RawTileView is immutable after parse.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/huge_page_array.hpp"
#include "common/result.hpp"

namespace shadowtiles {

inline constexpr uint8_t kRawTileMagic[4] = {'S', 'T', 'R', 'W'};  // FORMAT
inline constexpr uint16_t kRawTileFormatVersion = 1;                // FORMAT
inline constexpr size_t kRawTileHeaderSize = 12;                    // FORMAT
inline constexpr uint32_t kRawTileMaxSize = 1u << 14;

// Precondition: lower.size() == size * size, size a power of two <= kRawTileMaxSize.
std::vector<uint8_t> encode_raw_tile(uint32_t size, std::span<const float> lower);

class RawTileView {
 public:
  static Result<RawTileView> parse(std::span<const uint8_t> payload);
  uint32_t size() const { return size_; }
  float value(uint32_t u, uint32_t v) const { return values_[size_t(v) * size_ + u]; }
  // Texels of the kw x kh box at (u0, v0) (inside the tile) with threshold <= value: PCF reads the
  // box's rows straight from the array.
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const {
    uint32_t lit = 0;
    for (const float* row = &values_[size_t(v0) * size_ + u0]; kh > 0; --kh, row += size_)
      for (uint32_t i = 0; i < kw; ++i) lit += threshold <= row[i];
    return lit;
  }
  size_t memory_bytes() const { return values_.size() * sizeof(float); }

 private:
  uint32_t size_ = 0;
  // In 2 MiB pages where the kernel allows: a 2048^2 tile's first touch (its decode) then faults 8
  // times, not 4096 (bunny 16384^2, cold 1M-point raw batch 3.5 -> 1.7 s). Lookup rates did not move
  // (docs/client.md, session 30): on this VM the host's own 4 KiB tables still set the walks.
  HugePageArray<float> values_;
};

}  // namespace shadowtiles
