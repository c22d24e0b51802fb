// Field reads of a DAG-MH payload (codec/dagmh_format.hpp), shared by DagMhTileView's parse and
// its walks (codec/dagmh_decoder.cpp): fixed-width little-endian integers, bounded 64-bit loads,
// per-mask child tables and popcounts. All inline, so they compile into each caller's ISA clone.
// Thread safety: pure functions and constant tables.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>

#include "codec/dagmh_format.hpp"

namespace shadowtiles::dagmh_reads {

namespace F = dagmh_format;

// Fixed-size reads per width: a memcpy of runtime length would be a library call on the hot path.
inline uint32_t load_uint(const uint8_t* p, unsigned width) {
  switch (width) {
    case 1: return p[0];
    case 2: return uint32_t(p[0]) | (uint32_t(p[1]) << 8);
    case 3: return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16);
    default: {
      uint32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
  }
}
inline unsigned child_index(uint32_t u, uint32_t v, unsigned shift) {
  return ((u >> shift) & 1u) | (((v >> shift) & 1u) << 1);
}
// Per mask and child: present children before it (rank in the count list) and children with refs
// before it, plus the ref count; table reads instead of bit loops on every step.
struct MaskInfo {
  uint8_t present_before[4];
  uint8_t refs_before[4];
  uint8_t refs;
};
constexpr std::array<MaskInfo, 256> make_mask_info() {
  std::array<MaskInfo, 256> table{};
  for (unsigned mask = 0; mask < 256; ++mask) {
    MaskInfo info{};
    uint8_t present = 0, refs = 0;
    for (unsigned i = 0; i < 4; ++i) {
      info.present_before[i] = present;
      info.refs_before[i] = refs;
      const unsigned code = F::child_code(uint8_t(mask), i);
      present += code != 0;
      refs += code >= F::kCodeTreelet;
    }
    info.refs = refs;
    table[mask] = info;
  }
  return table;
}
inline constexpr std::array<MaskInfo, 256> kMaskInfo = make_mask_info();
// Byte popcounts by table: without -mpopcnt, std::popcount is a library call.
constexpr std::array<uint8_t, 256> make_popcounts() {
  std::array<uint8_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) t[i] = uint8_t((i & 1) + t[i / 2]);
  return t;
}
inline constexpr std::array<uint8_t, 256> kPopcount = make_popcounts();
// Bit-parallel popcount: a few ALU ops, no table and no libgcc call (the build has no -mpopcnt).
inline unsigned popcount64(uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return unsigned((x * 0x0101010101010101ULL) >> 56);
}
// Up to 8 little-endian bytes at p, never reading at or past `end` (missing bytes read as 0).
inline uint64_t load_u64_before(const uint8_t* p, const uint8_t* end) {
  uint64_t x = 0;
  if (end - p >= 8) {
    std::memcpy(&x, p, 8);
    return x;
  }
  for (unsigned q = 0; p + q < end; ++q) x |= uint64_t(p[q]) << (8 * q);
  return x;
}
inline uint64_t low_bits(unsigned n) { return n >= 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1; }
// Set bits of a byte bitmap below bit `bit`.
inline unsigned popcount_below(const uint8_t* bytes, unsigned bit) {
  unsigned n = 0, q = 0;
  for (; q + 8 <= bit; q += 8) n += kPopcount[bytes[q / 8]];
  if (bit > q) n += kPopcount[bytes[q / 8] & ((1u << (bit - q)) - 1u)];
  return n;
}

}  // namespace shadowtiles::dagmh_reads
