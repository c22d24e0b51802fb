// Morton (Z-order) codes of 2D texel coordinates (up to 2^32 per side): interleaved bits, u in the
// even bits. Aligned power-of-two squares (tiles, quadtree nodes) are contiguous key ranges, so one
// sort by key orders points by tile and along the curve inside each tile.
// Thread safety: pure functions.
#pragma once

#include <cstdint>

namespace shadowtiles {

inline uint64_t morton_spread(uint32_t x) {
  uint64_t v = x;
  v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
  v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
  v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v << 2)) & 0x3333333333333333ull;
  v = (v | (v << 1)) & 0x5555555555555555ull;
  return v;
}
inline uint32_t morton_compact(uint64_t v) {
  v &= 0x5555555555555555ull;
  v = (v | (v >> 1)) & 0x3333333333333333ull;
  v = (v | (v >> 2)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v >> 4)) & 0x00FF00FF00FF00FFull;
  v = (v | (v >> 8)) & 0x0000FFFF0000FFFFull;
  v = (v | (v >> 16)) & 0x00000000FFFFFFFFull;
  return uint32_t(v);
}
inline uint64_t morton_encode(uint32_t u, uint32_t v) { return morton_spread(u) | (morton_spread(v) << 1); }
// The same code for u, v < 2^16, both spread at once in one 64-bit word (u low, v high): half the
// operations of two morton_spread calls, for the batch query's per-point pass.
inline uint32_t morton_encode16(uint32_t u, uint32_t v) {
  uint64_t x = uint64_t(u & 0xFFFF) | (uint64_t(v & 0xFFFF) << 32);
  x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;
  x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | (x << 2)) & 0x3333333333333333ull;
  x = (x | (x << 1)) & 0x5555555555555555ull;
  return uint32_t(x) | uint32_t(x >> 31);
}
inline uint32_t morton_u(uint64_t key) { return morton_compact(key); }
inline uint32_t morton_v(uint64_t key) { return morton_compact(key >> 1); }

}  // namespace shadowtiles
