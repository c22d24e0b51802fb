// Per-tile info records (LMDB database `tileinfo`, same key as the tile's blob in `tiles`): what a
// merge or an inspector needs about a stored tile without decompressing or decoding it — the
// tile's root interval (for the top levels and skip list) and its blob and payload sizes.
// Written by the builder in the same transaction as the blob, so the two never disagree.
// FORMAT-defining layout, 28 bytes little-endian:
//   offset  0  format_version u8   (kTileInfoFormatVersion)
//   offset  1  flags          u8   bit 0: has_root (hierarchical methods); other bits zero
//   offset  2  reserved       u16  zero
//   offset  4  root_lower     f32
//   offset  8  root_upper     f32  (+inf allowed: a miss)
//   offset 12  blob_bytes     u64  stored blob size (header + zstd frame)
//   offset 20  payload_bytes  u64  the method's payload before zstd (blob raw_size)
// Errors: wrong size, unknown version, unknown flag bits, NaN or inverted root → corrupt_data;
// a newer version → unsupported. Safe on untrusted input. Thread safety: pure functions.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "common/result.hpp"

namespace shadowtiles::store {

inline constexpr uint8_t kTileInfoFormatVersion = 1;  // FORMAT
inline constexpr size_t kTileInfoSize = 28;           // FORMAT

struct TileInfo {
  bool has_root = false;
  float root_lower = 1.0f;  // a miss unless has_root
  float root_upper = 1.0f;
  uint64_t blob_bytes = 0;
  uint64_t payload_bytes = 0;
  bool operator==(const TileInfo&) const = default;
};

std::array<uint8_t, kTileInfoSize> encode_tile_info(const TileInfo& info);
Result<TileInfo> decode_tile_info(std::span<const uint8_t> bytes);

}  // namespace shadowtiles::store
