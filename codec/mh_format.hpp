// MH/MMH tile payload format, shared by the encoder (builder/mh_encoder) and the decoder
// (codec/mh_decoder). FORMAT-DEFINING: changing anything here changes stored bytes; bump
// kMhFormatVersion and keep golden payloads of released versions in tests. Full description:
// docs/mh.md.
//
// Layout (all integers little-endian, no alignment):
//   header (kMhHeaderBytes) | skip list (optional) | node stream
// Node stream = child blocks. A block holds the children of one node whose 8-bit mask gives the
// 2-bit code of each child i (bits 2i..2i+1): 00 absent, 01 leaf (value, no children), 10 empty
// (children, no value), 11 inner (value and children). Block = [one record per child with
// children, in child order][one float32 value per child with a value, in child order]; a record is
// the child's own mask (1 byte) + the byte offset of its child block in the node stream
// (offset_width bytes). Every offset points forward (the decoder requires it; the encoder writes
// blocks in preorder, earlier stores tallest subtree first); MMH shares a block between records by
// giving them the same offset.
// Skip list entry (level S, 2^S x 2^S, row-major): float32 value (deepest value on the path down to
// level S), mask of the level-S node (0 when the walk ends above or at S), offset of its block.
#pragma once

#include <cstddef>
#include <cstdint>

namespace shadowtiles::mh_format {

inline constexpr uint8_t kMagic[4] = {'S', 'T', 'M', 'H'};
inline constexpr uint16_t kFormatVersion = 1;

inline constexpr uint16_t kFlagSkipList = 1u << 0;  // a skip list follows the header
inline constexpr uint16_t kFlagMerged = 1u << 1;    // informational: blocks may be shared (MMH)
inline constexpr uint16_t kKnownFlags = kFlagSkipList | kFlagMerged;

// Header field offsets.
inline constexpr size_t kOffMagic = 0;        // 4 bytes
inline constexpr size_t kOffVersion = 4;      // u16
inline constexpr size_t kOffFlags = 6;        // u16
inline constexpr size_t kOffSize = 8;         // u32 texels per side, power of two
inline constexpr size_t kOffLevels = 12;      // u8 log2(size)
inline constexpr size_t kOffOffsetWidth = 13; // u8 bytes per block offset, 1..4
inline constexpr size_t kOffSkipLevel = 14;   // u8 skip list level S (0 when absent)
inline constexpr size_t kOffRootMask = 15;    // u8 codes of the root's children (0: root is a leaf)
inline constexpr size_t kOffRootValue = 16;   // f32 root value (the root always has one)
inline constexpr size_t kOffRootBlock = 20;   // u32 offset of the root's child block (0 if leaf)
inline constexpr size_t kOffStreamBytes = 24; // u32 node stream size
inline constexpr size_t kOffBlockCount = 28;  // u32 distinct blocks in the stream
inline constexpr size_t kOffRecordCount = 32; // u32 records (nodes with children) in the stream
inline constexpr size_t kOffValueCount = 36;  // u32 values in the stream (root excluded)
inline constexpr size_t kHeaderBytes = 40;

inline constexpr unsigned kMaxLevels = 24;     // decoder limit (u, v are 32-bit)
inline constexpr unsigned kMaxSkipLevel = 10;  // 4^10 entries at most
inline constexpr unsigned kDefaultSkipLevel = 6;

// Child codes.
inline constexpr unsigned kCodeAbsent = 0, kCodeLeaf = 1, kCodeEmpty = 2, kCodeInner = 3;
inline constexpr unsigned child_code(uint8_t mask, unsigned child) { return (mask >> (2 * child)) & 3u; }

inline constexpr size_t record_bytes(unsigned offset_width) { return 1 + offset_width; }
inline constexpr unsigned branch_children(uint8_t mask) {  // children with code 10 or 11
  return ((mask >> 1) & 1) + ((mask >> 3) & 1) + ((mask >> 5) & 1) + ((mask >> 7) & 1);
}
inline constexpr unsigned valued_children(uint8_t mask) {  // children with code 01 or 11
  return (mask & 1) + ((mask >> 2) & 1) + ((mask >> 4) & 1) + ((mask >> 6) & 1);
}
inline constexpr size_t block_bytes(uint8_t mask, unsigned offset_width) {
  return branch_children(mask) * record_bytes(offset_width) + valued_children(mask) * 4;
}
inline constexpr size_t skip_entry_bytes(unsigned offset_width) { return 4 + 1 + offset_width; }

}  // namespace shadowtiles::mh_format
