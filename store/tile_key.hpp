// Tile keys of the `tiles` database (docs/architecture.md §9): 10 bytes, FORMAT-defining layout
//   method u8 | level u8 | x u32 big-endian | y u32 big-endian
// Big-endian fixed width makes memcmp (LMDB's key order) equal numeric (method, level, x, y) order,
// so one method and level form a contiguous key range (see tile_key_prefix).
// Errors: decode_tile_key returns invalid_input for a wrong length or an unknown method byte.
// Thread safety: pure functions. Safe on untrusted input.
#pragma once

#include <array>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <span>

#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles::store {

inline constexpr size_t kTileKeySize = 10;       // FORMAT
inline constexpr size_t kTileKeyPrefixSize = 2;  // FORMAT: method + level

struct TileKey {
  Method method;
  uint8_t level;
  uint32_t x;
  uint32_t y;
  auto operator<=>(const TileKey&) const = default;
};

std::array<uint8_t, kTileKeySize> encode_tile_key(const TileKey& key);

// Exactly kTileKeySize bytes with a known method byte, else invalid_input.
Result<TileKey> decode_tile_key(std::span<const uint8_t> bytes);

// The first bytes shared by every key of one method and level, for Store::for_each.
std::array<uint8_t, kTileKeyPrefixSize> tile_key_prefix(Method method, uint8_t level);

}  // namespace shadowtiles::store
