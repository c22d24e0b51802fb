// Tile previews (issue 17): a small picture of one stored tile of one method, written by the build
// beside the tile (LMDB database `preview`, same key and same transaction as the tile blob), so the
// inspector's coarse zooms (/v1/render) never decompress a tile.
//
// A preview samples the tile on a P x P grid (P = min(kPreviewSize, tile side)); preview texel
// (i, j) is tile texel (i * step + step / 2, j * step + step / 2) with step = tile side / P. Point
// samples, not averages, so the three planes describe one texel each and value lies in
// [lower, lower + width] there. Planes (float32, row-major, j * P + i):
//   lower  the texel's first-hit depth (1 for a miss): the top-down view of the world
//   value  the method's stored (decoded) value at the texel
//   width  upper - lower of the texel's interval (+inf for a miss, 0 for an open surface)
//
// FORMAT: the record is a blob (store/blob.hpp: zstd, XXH64 over header and payload, the tile's
// method in the header) whose payload is
//   offset  0  magic "STPV"              4 bytes
//   offset  4  version u16 (kPreviewFormatVersion)
//   offset  6  plane count u16 (3)
//   offset  8  P u32
//   offset 12  step u32
//   offset 16  lower[P*P], value[P*P], width[P*P]   little-endian float32
// Errors: decode_preview → corrupt_data (blob checks, wrong magic, sizes, another method than
// expected), unsupported (newer version). Safe on untrusted input.
// Thread safety: pure functions.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles::store {

inline constexpr uint32_t kPreviewSize = 64;          // FORMAT default side
inline constexpr uint16_t kPreviewFormatVersion = 1;  // FORMAT
inline constexpr uint8_t kPreviewMagic[4] = {'S', 'T', 'P', 'V'};
inline constexpr size_t kPreviewHeaderSize = 16;

struct TilePreview {
  uint32_t size = 0;  // P
  uint32_t step = 1;  // tile texels per preview texel, per axis
  std::vector<float> lower, value, width;  // P * P each

  size_t index(uint32_t i, uint32_t j) const { return size_t(j) * size + i; }
  size_t memory_bytes() const { return (lower.size() + value.size() + width.size()) * sizeof(float); }
};

// The preview side for a tile side (both powers of two).
inline uint32_t preview_size_for(uint32_t tile_size) { return tile_size < kPreviewSize ? tile_size : kPreviewSize; }

// Precondition: preview.size >= 1 and the three planes hold size^2 values.
std::vector<uint8_t> encode_preview(Method method, const TilePreview& preview, int zstd_level = 3);
// Checks the blob and its payload; the blob's method must be `expected`.
Result<TilePreview> decode_preview(std::span<const uint8_t> blob, Method expected);

}  // namespace shadowtiles::store
