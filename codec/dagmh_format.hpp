// DAG-MH tile payload format, shared by the encoder (builder/dagmh_encoder) and the decoder
// (codec/dagmh_decoder). FORMAT-DEFINING: changing anything here changes stored bytes; bump
// kFormatVersion and keep golden payloads of released versions in tests. Full description:
// docs/dagmh.md.
//
// Layout (all integers little-endian, no alignment):
//   header (kHeaderBytes) | DAG nodes | treelets | chunk offset table | chunk data
// DAG node: u8 mask (2-bit code per child i: 00 absent, 01 leaf value, 10 treelet, 11 DAG node),
//   u8 flags (bit 0: the node itself has a value), one ref (ref_width bytes) per child with code
//   10/11 in child order, then for every present child but the first (in child order) the number of
//   values in the node's children before that child (count_width bytes).
// Treelet: the valued-node bitmap of a subtree of at most H levels, depth-first (bit of a node at
//   depth n with child indices l0..l(n-1): n + sum l_k * S(H-1-k), S(h) = (4^h - 1) / 3),
//   treelet_bytes(H) bytes, LSB first.
// Chunk: f32 representative | u8 b | if b > 0: bitmap of the chunk's values that differ from the
//   representative | if 1 <= b <= 24: f32 c_l, f32 c_f, then one b-bit multiplier m per differing
//   value (LSB-first bit stream), value = dequantize(c_l, c_f, m) | if b == 32: f32 per differing value.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace shadowtiles::dagmh_format {

inline constexpr uint8_t kMagic[4] = {'S', 'T', 'D', 'G'};
inline constexpr uint16_t kFormatVersion = 1;

// Header field offsets.
inline constexpr size_t kOffMagic = 0;         // 4 bytes
inline constexpr size_t kOffVersion = 4;       // u16
inline constexpr size_t kOffFlags = 6;         // u16, must be 0
inline constexpr size_t kOffSize = 8;          // u32 texels per side, 2^levels
inline constexpr size_t kOffLevels = 12;       // u8
inline constexpr size_t kOffTreeletHeight = 13;  // u8 H, 2..5
inline constexpr size_t kOffRefWidth = 14;     // u8 1..4
inline constexpr size_t kOffCountWidth = 15;   // u8 1..4
inline constexpr size_t kOffChunkOffsetWidth = 16;  // u8 1..4
inline constexpr size_t kOffRootKind = 17;     // u8 kCodeLeaf / kCodeTreelet / kCodeDag
inline constexpr size_t kOffChunkSize = 18;    // u16 values per chunk
inline constexpr size_t kOffRootRef = 20;      // u32 treelet index or DAG offset (0 for a leaf)
inline constexpr size_t kOffDagBytes = 24;     // u32
inline constexpr size_t kOffTreeletCount = 28; // u32
inline constexpr size_t kOffValueCount = 32;   // u32 values in the depth-first list (>= 1)
inline constexpr size_t kOffChunkBytes = 36;   // u32 chunk data bytes
inline constexpr size_t kHeaderBytes = 40;

inline constexpr unsigned kMaxLevels = 24;
inline constexpr unsigned kMinTreeletHeight = 2, kMaxTreeletHeight = 5;
inline constexpr unsigned kMaxChunkSize = 1024;
inline constexpr unsigned kMaxQuantBits = 24;  // float(m) is exact up to 2^24
inline constexpr unsigned kRawBits = 32;       // b == 32: differing values stored as raw floats

// Child codes in a DAG node mask.
inline constexpr unsigned kCodeAbsent = 0, kCodeLeaf = 1, kCodeTreelet = 2, kCodeDag = 3;
inline constexpr unsigned child_code(uint8_t mask, unsigned child) { return (mask >> (2 * child)) & 3u; }
inline constexpr unsigned ref_children(uint8_t mask) {  // codes 10 / 11
  return ((mask >> 1) & 1) + ((mask >> 3) & 1) + ((mask >> 5) & 1) + ((mask >> 7) & 1);
}
inline constexpr unsigned present_children(uint8_t mask) {
  unsigned n = 0;
  for (unsigned i = 0; i < 4; ++i) n += child_code(mask, i) != 0;
  return n;
}
inline constexpr size_t node_bytes(uint8_t mask, unsigned ref_width, unsigned count_width) {
  const unsigned present = present_children(mask);
  return 2 + ref_children(mask) * ref_width + (present > 0 ? present - 1 : 0) * count_width;
}

// Nodes of a complete subtree with h levels.
inline constexpr uint32_t complete_nodes(unsigned h) { return ((uint32_t(1) << (2 * h)) - 1) / 3; }
inline constexpr size_t treelet_bits(unsigned H) { return complete_nodes(H); }
inline constexpr size_t treelet_bytes(unsigned H) { return (treelet_bits(H) + 7) / 8; }

// The one float expression that turns a multiplier into a value: the encoder verifies every value
// with exactly this, so quantisation is lossless by construction. std::fma is correctly rounded
// everywhere (no dependence on -ffp-contract or FMA hardware).
inline float dequantize(float c_l, float c_f, uint32_t m) { return std::fma(c_f, float(m), c_l); }

inline constexpr size_t bitmap_bytes(unsigned n) { return (n + 7) / 8; }

}  // namespace shadowtiles::dagmh_format
