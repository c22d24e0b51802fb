// SST (sparse shadow tree, docs/architecture.md §8, seed 002) tile payload format, shared by the encoder
// (builder/sst_encoder) and the decoder (codec/sst_tile_view). FORMAT-DEFINING: changing anything
// here changes stored bytes; bump kFormatVersion. Full description: docs/sst.md.
//
// Layout (all integers little-endian, no alignment):
//   header (kHeaderBytes) | grid: blocks_per_side^2 u32 block offsets, row-major | node section
// The tile is cut into blocks of block_side^2 texels (block_side = min(kBlockSide, size)). Each block
// is a quadtree stored depth-first, children in Morton order (0: u low/v low, 1: u high, 2: v high,
// 3: both high). A block starts with u8 offset width w (1..4), then its root node. Blocks follow
// each other in Morton order of the block grid and tile the node section exactly; a grid offset is
// relative to the node section's start.
// Node: u8 tag (low 3 bits: kind; high 5 bits: plane exponent E, zero for other kinds), then
//   internal: 3 x w-byte child offsets (children 1..3, relative to the end of this record; child 0
//             follows the record immediately)
//   one:      nothing (value 1.0: right for misses [1, +inf) and anything whose interval holds 1)
//   constant: f32 value
//   plane:    u24 A, i16 B, i16 C: value(x, y) = plane_value(A, B, C, E, x, y), x, y node-local
//             texel offsets (8 bytes in all: the talk's 62-bit plane plus the kind flag)
//   dense:    side^2 f32 values, row-major (2 <= side <= kMaxDenseSide): the fallback where no
//             plane fits a small node (open geometry has zero-width intervals)
#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace shadowtiles::sst_format {

inline constexpr uint8_t kMagic[4] = {'S', 'T', 'S', 'T'};
inline constexpr uint16_t kFormatVersion = 1;

// Header field offsets.
inline constexpr size_t kOffMagic = 0;          // 4 bytes
inline constexpr size_t kOffVersion = 4;        // u16
inline constexpr size_t kOffFlags = 6;          // u16, must be 0
inline constexpr size_t kOffSize = 8;           // u32 texels per side, a power of two
inline constexpr size_t kOffBlockSide = 12;     // u32 min(kBlockSide, size)
inline constexpr size_t kOffBlocksPerSide = 16; // u32 size / block_side
inline constexpr size_t kOffNodeBytes = 20;     // u32 node section bytes
inline constexpr size_t kHeaderBytes = 24;

inline constexpr uint32_t kBlockSide = 128;
inline constexpr uint32_t kMaxSize = uint32_t(1) << 20;
inline constexpr uint32_t kMaxDenseSide = 8;
inline constexpr unsigned kMaxOffsetWidth = 4;

enum Kind : uint8_t { kInternal = 0, kOne = 1, kConstant = 2, kPlane = 3, kDense = 4 };
inline constexpr unsigned kKindCount = 5;
inline constexpr uint8_t kind_of(uint8_t tag) { return tag & 7u; }
inline constexpr uint8_t exponent_of(uint8_t tag) { return tag >> 3; }
inline constexpr uint8_t make_tag(Kind kind, unsigned exponent = 0) { return uint8_t(kind | (exponent << 3)); }

inline constexpr size_t kInternalFixedBytes = 1;  // plus 3 * w
inline constexpr size_t kConstantBytes = 5;
inline constexpr size_t kPlaneBytes = 8;
inline constexpr size_t dense_bytes(uint32_t side) { return 1 + size_t(side) * side * 4; }
inline constexpr size_t internal_bytes(unsigned width) { return kInternalFixedBytes + 3 * size_t(width); }

// Plane quantisation: a = A * 2^-23 (A < 2^24: [0, 2)), b = B * 2^-(14 + E), c = C * 2^-(14 + E)
// (|slope| < 2 texel^-1 at E = 0, steps down to 2^-45). Every factor is exact in float.
inline constexpr unsigned kOffsetBits = 24;
inline constexpr uint32_t kMaxOffset = (uint32_t(1) << kOffsetBits) - 1;
inline constexpr int kOffsetShift = 23;
inline constexpr int kSlopeShiftBase = 14;
inline constexpr unsigned kMaxExponent = 31;
inline constexpr int32_t kMaxSlope = 32767;

// The one float expression that turns a stored plane into a value: the encoder verifies every
// texel with exactly this, so the quantised planes are lossless by construction. std::fma is
// correctly rounded everywhere (no dependence on -ffp-contract or FMA hardware); the scalings are
// products with powers of two, hence exact.
// 2^-(kSlopeShiftBase + E), built from its exponent bits (E <= kMaxExponent keeps it normal).
inline float slope_step(unsigned E) { return std::bit_cast<float>(uint32_t(127 - kSlopeShiftBase - int(E & 31u)) << 23); }
inline float plane_value(uint32_t A, int16_t B, int16_t C, unsigned E, uint32_t x, uint32_t y) {
  const float a = float(A) * 0x1p-23f;
  const float step = slope_step(E);
  const float b = float(B) * step, c = float(C) * step;
  return std::fma(c, float(y), std::fma(b, float(x), a));
}

// Plane record body (after the tag): u24 A | i16 B | i16 C.
struct PlaneBits {
  uint32_t A = 0;
  int16_t B = 0, C = 0;
  uint8_t E = 0;
  float value(uint32_t x, uint32_t y) const { return plane_value(A, B, C, E, x, y); }
};

inline PlaneBits load_plane(const uint8_t* tag) {
  PlaneBits p;
  p.E = exponent_of(tag[0]);
  p.A = uint32_t(tag[1]) | uint32_t(tag[2]) << 8 | uint32_t(tag[3]) << 16;
  uint16_t b, c;
  std::memcpy(&b, tag + 4, 2);
  std::memcpy(&c, tag + 6, 2);
  p.B = int16_t(b);
  p.C = int16_t(c);
  return p;
}

}  // namespace shadowtiles::sst_format
