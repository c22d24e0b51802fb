// CPVS construction (Kämpe, Sintorn, Assarsson 2015 on Sintorn et al. 2014): a tile's dual depth ->
// a DAG of binary visibility over (u, v, depth step), in memory, ready to serialise
// (builder/cpvs_serializer.hpp). Built top-down in Z order with a min-max hierarchy: a node whose
// voxels are all lit-or-free (all shadowed-or-free) becomes a constant child without descending.
// Children are finished before their parent, so a node is merged with an identical one before the
// tree ever holds a duplicate: per level, nodes are keyed by (child codes, canonical child ids);
// equal keys mean identical subtrees. The hash only picks the bucket; keys are always compared in
// full (CpvsBuildOptions::hash_bits can shrink the hash to prove it).
// Free voxels in leaves: prefer a mask already built (free -> lit first, then free -> shadowed), so
// the number of unique leaves stays locally minimal; otherwise free -> lit.
// Errors: invalid_input for malformed intervals (NaN, lower > upper, size not a power of two).
// Thread safety: stateless; call concurrently.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "codec/cpvs_format.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct CpvsBuildOptions {
  // 4x4x4 measured smaller than the original's 8x8x1 slabs on every scene tried (docs/cpvs.md).
  cpvs::LeafLayout layout = cpvs::LeafLayout::cube4;
  // Bits of the node hash actually used (1..64). Test-only below 64: forces collisions so that the
  // full key comparison, not the hash, decides what merges.
  unsigned hash_bits = 64;
  // Resolve a leaf's free voxels to match a mask already built when one of the two candidates does
  // (off: free voxels always lit; kept to measure what the rule saves).
  bool reuse_free_choice = true;
};

struct CpvsNode {
  uint16_t codes = 0;                 // 2-bit child codes (codec/cpvs_format.hpp)
  std::array<uint32_t, 8> refs{};     // ids in the next level (or leaf ids), code-2 children in order; rest 0
  uint8_t ref_count = 0;
  bool operator==(const CpvsNode&) const = default;
};

struct CpvsBuildStats {
  uint64_t nodes_visited = 0;    // internal nodes built before merging
  uint64_t leaves_visited = 0;   // leaf masks built before merging
  uint64_t leaves_matched_by_free_choice = 0;  // leaves merged only thanks to the free-voxel choice
  double pyramid_seconds = 0;
  double dag_seconds = 0;
};

struct CpvsDag {
  uint32_t tile_size = 0;
  uint32_t depth_steps = 0;
  cpvs::LeafLayout layout = cpvs::LeafLayout::slab8;
  unsigned root_code = cpvs::kCodeLit;
  // levels[l]: the unique nodes of side depth_steps >> l, by id; levels[0] holds the root (id 0)
  // when root_code is kCodeRef. Always level_count_for(depth_steps) levels.
  std::vector<std::vector<CpvsNode>> levels;
  std::vector<uint64_t> leaves;  // unique masks, bit 1 = shadowed
  CpvsBuildStats stats;
};

// `map_resolution`: side of the whole map; depth is quantised to cpvs::depth_steps_for(map, tile) steps.
Result<CpvsDag> build_cpvs_dag(const TileIntervals& intervals, uint32_t map_resolution,
                               const CpvsBuildOptions& options = {});

}  // namespace shadowtiles
