// MhHierarchy: the builder-side form of an MH or MMH (docs/architecture.md §5, §6), between construction
// (mh_builder), merging (mmh_merger) and encoding (mh_encoder). Nodes are grouped in *blocks*: the
// children of one node. Each node carries, instead of a value, its validity interval: any value
// inside it keeps every texel that resolves to the node (deepest valued node on its path) exact.
// The encoder picks the values (mh_value_for).
//
// Child codes (2 bits per child i in a block mask): 00 absent, 01 leaf, 10 empty, 11 inner, as in
// the payload format (codec/mh_format.hpp). A block is shared by several parents in an MMH.
// Thread safety: plain value type.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct MhHierarchy {
  uint32_t size = 0;    // texels per side, power of two
  unsigned levels = 0;  // log2(size); level 0 = root, level `levels` = texels

  DepthInterval root;         // the root always has a value
  uint8_t root_mask = 0;      // codes of the root's children; 0 = the root is a leaf
  uint32_t root_block = 0;    // block of the root's children (when root_mask != 0)

  // Per block b: codes of its entries, index of its first entry with children in child_block,
  // index of its first valued entry in intervals. Entries with children (codes 10, 11) and valued
  // entries (01, 11) are contiguous per block, in child order.
  std::vector<uint8_t> block_mask;
  std::vector<uint32_t> block_first_child;
  std::vector<uint32_t> block_first_value;
  std::vector<uint32_t> child_block;     // per entry with children: the block of its children
  std::vector<DepthInterval> intervals;  // per valued entry: its validity interval

  size_t block_count() const { return block_mask.size(); }
};

// Counts of a hierarchy's nodes as stored (shared blocks once) and as a tree (sharing expanded).
struct MhNodeCounts {
  uint64_t blocks = 0, inner = 0, empty = 0, leaves = 0;  // reachable, distinct; root included
  uint64_t tree_nodes = 0;                                // all nodes of the expanded tree
};
MhNodeCounts count_nodes(const MhHierarchy& h);
// count_nodes without tree_nodes (left 0): the stored counts alone, one breadth-first pass without
// the expanded tree's per-block memo and recursion (the builder's reference size, per tile and method).
MhNodeCounts count_stored_nodes(const MhHierarchy& h);

// Checks indices, masks and depth (no path longer than `levels`). Errors: invalid_input.
Status check_structure(const MhHierarchy& h);

// Value the encoder stores for a validity interval: the midpoint, kept inside the interval;
// open ends (misses are [1, +inf)) use the finite end, so every stored value is finite.
float mh_value_for(const DepthInterval& interval);

// What the top levels need from a tile (docs/architecture.md §5 "tiled build"): the root's validity interval.
// The tiles' roots, with absent tiles as [1, +inf), form the texels of the top-level MH.
struct MhTileSummary {
  DepthInterval root;
};
MhTileSummary summarize(const MhHierarchy& h);

}  // namespace shadowtiles
