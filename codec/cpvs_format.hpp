// CPVS tile payload format (compact precomputed voxelized shadows, docs/architecture.md §8, seed 004), shared
// by the encoder (builder/cpvs_*) and the decoder (codec/cpvs_decoder). FORMAT-DEFINING: changing
// anything here changes stored bytes; bump kFormatVersion. Full description: docs/cpvs.md.
//
// The tile is a cube of N x N x N voxels (u, v, depth step), N = depth_steps(): texels outside the
// tile (u or v >= tile size) exist only so the octree is cubic and are never queried. Voxel bit 1 =
// shadowed. Internal levels have sides N, N/2, ..., 8; the children of the side-8 level are 64-bit
// leaf masks: 4x4x4 octants (LeafLayout::cube4) or eight 8x8x1 depth slices (LeafLayout::slab8).
//
// Layout (all integers little-endian, no alignment):
//   header (kHeaderBytes) | level table (level_count x kLevelEntryBytes) | level 0 nodes | ... |
//   level L-1 nodes | leaf masks (leaf_count x u64)
// Node: u16 child codes (2 bits per child, child i at bits 2i..2i+1: 0 lit, 1 shadowed, 2 ref,
//   3 invalid), then one ref (the level's ref_width bytes) per code-2 child, in child order. A ref
//   is the byte offset of a node in the next level's region, or a leaf index from the last level.
// Octree child index: bit 0 = upper u half, bit 1 = upper v half, bit 2 = upper depth half.
#pragma once

#include "common/byte_order.hpp"

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace shadowtiles::cpvs {

inline constexpr uint8_t kMagic[4] = {'S', 'T', 'C', 'V'};
inline constexpr uint16_t kFormatVersion = 1;

inline constexpr size_t kOffMagic = 0;        // 4 bytes
inline constexpr size_t kOffVersion = 4;      // u16
inline constexpr size_t kOffLayout = 6;       // u8 LeafLayout
inline constexpr size_t kOffRootCode = 7;     // u8 child code of the whole cube
inline constexpr size_t kOffTileSize = 8;     // u32, power of two, <= depth steps
inline constexpr size_t kOffDepthSteps = 12;  // u32 N, power of two in [kMinSide, kMaxDepthSteps]
inline constexpr size_t kOffLevelCount = 16;  // u32 = log2(N) - 2
inline constexpr size_t kOffLeafCount = 20;   // u32
inline constexpr size_t kHeaderBytes = 24;
// Level table entry: u32 byte size of the level's node region, u8 ref width (1..4), 3 zero bytes.
inline constexpr size_t kLevelEntryBytes = 8;

inline constexpr uint32_t kMinSide = 8;  // the last internal level's side
inline constexpr uint32_t kMaxDepthSteps = 1u << 20;

enum class LeafLayout : uint8_t {
  cube4 = 0,  // 4x4x4 voxels, bit = (u & 3) | (v & 3) << 2 | (z & 3) << 4
  slab8 = 1,  // 8x8 texels at one depth step, bit = (u & 7) | (v & 7) << 3
};

inline constexpr unsigned kCodeLit = 0, kCodeShadowed = 1, kCodeRef = 2;

inline constexpr unsigned child_code(uint16_t codes, unsigned child) { return (codes >> (2 * child)) & 3u; }
// Bit 2i set when child i is a ref (code 10).
inline constexpr uint16_t ref_bits(uint16_t codes) { return uint16_t((codes >> 1) & ~codes & 0x5555u); }
inline constexpr bool has_invalid_code(uint16_t codes) { return ((codes >> 1) & codes & 0x5555u) != 0; }
// Set bits of a mask whose bits are all at even positions of 16 (ref_bits): two SWAR steps inline.
// std::popcount is a libgcc call on baseline x86-64 (no POPCNT): 17 % of a CPVS point lookup.
inline constexpr unsigned even_bit_count(uint32_t pairs) {
  pairs = (pairs & 0x3333u) + ((pairs >> 2) & 0x3333u);  // 4-bit fields of 0..2
  pairs = (pairs + (pairs >> 4)) & 0x0F0Fu;              // bytes of 0..4
  return (pairs + (pairs >> 8)) & 0x1Fu;
}
inline constexpr unsigned ref_count(uint16_t codes) { return even_bit_count(ref_bits(codes)); }
// Position of child `child`'s ref among the node's refs.
inline constexpr unsigned ref_rank(uint16_t codes, unsigned child) {
  return even_bit_count(unsigned(ref_bits(codes)) & ((1u << (2 * child)) - 1u));
}

// Depth steps (the cube side) for a map of side `map_resolution` cut into tiles of `tile_size`:
// the map's side (docs/architecture.md §8), at least the tile side and kMinSide, rounded up to a power of two.
inline uint32_t depth_steps_for(uint32_t map_resolution, uint32_t tile_size) {
  uint32_t n = map_resolution > tile_size ? map_resolution : tile_size;
  if (n < kMinSide) n = kMinSide;
  return std::bit_ceil(n);
}
inline constexpr unsigned level_count_for(uint32_t depth_steps) {
  return unsigned(std::countr_zero(depth_steps)) - 2;
}

// Quantisation rule (format-defining). A receiver's biased normalised depth t falls in step
// floor(t * N), clamped to N - 1; t < 0 (and NaN) is in front of everything: lit.
inline constexpr int64_t kLitBeforeEverything = -1;
inline int64_t depth_step(float threshold, uint32_t depth_steps) {
  if (!(threshold >= 0.0f)) return kLitBeforeEverything;
  double step = std::floor(double(threshold) * double(depth_steps));
  return step >= double(depth_steps) ? int64_t(depth_steps) - 1 : int64_t(step);
}

// Per texel, the steps an interval [lower, upper] pins down: steps z < lit_end, up to and including
// the step holding `lower`, must be lit; steps z >= shadow_begin lie wholly behind `upper` and must
// be shadowed; steps in between are free (inside a closed object, or straddling `upper`).
// The entry's own step is lit, not free: every receiver the lower-bound map (raw) lights, biased
// depth <= lower, falls in a step <= lower's, so CPVS lights it too, under any tiling (a free step
// there was resolved per tile, so two tilings answered such receivers differently). The price: a
// receiver less than one step behind `lower` is lit.
struct StepBounds {
  uint32_t lit_end = 0;
  uint32_t shadow_begin = 0;
};
inline StepBounds step_bounds(float lower, float upper, uint32_t depth_steps) {
  const double n = double(depth_steps);
  double a = std::floor(double(lower) * n) + 1.0;
  a = a < 0 ? 0 : (a > n ? n : a);
  double b = std::isinf(upper) ? n : std::floor(double(upper) * n) + 1.0;
  b = b < a ? a : (b > n ? n : b);
  return {uint32_t(a), uint32_t(b)};
}

// A ref of `width` bytes (1..4).
// `width` in 1..4 (checked at parse): one load per width rather than a byte loop on the lookup path.
inline uint32_t load_ref(const uint8_t* in, unsigned width) {
  switch (width) {
    case 1: return in[0];
    case 2: return bytes::load_le<uint16_t>(in);
    case 3: return bytes::load_le<uint16_t>(in) | uint32_t(in[2]) << 16;
    default: return bytes::load_le<uint32_t>(in);
  }
}
inline unsigned ref_width_for(uint32_t max_ref) {
  return max_ref < (1u << 8) ? 1 : max_ref < (1u << 16) ? 2 : max_ref < (1u << 24) ? 3 : 4;
}

}  // namespace shadowtiles::cpvs
