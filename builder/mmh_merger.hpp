// MMH merging (docs/architecture.md §6; SBE16b): inside one tile, the children blocks of two nodes are shared
// when their subtrees have identical topology (same child codes at every node) and every pair of
// corresponding valued nodes has intersecting validity intervals. The kept block's intervals become
// the intersections, so its values (midpoints, chosen by the encoder) are exact for every sharer.
// Values are absolute: there is no relative mode (unsound under merging, see docs/architecture.md §6).
//
// Algorithm: topology hash and height per block, bottom-up; blocks in order of decreasing height
// (tallest first), each tested against the representatives of its (height, hash) bucket, most
// recent first (neighbours in breadth-first order are near in space), at most
// `max_tests_per_block` of them; a test first rejects on the subtrees' aggregate interval hulls,
// then compares the structure and intervals fully (hash equality is never trusted). First fit wins;
// a block that fits nowhere becomes a representative. A block whose intervals all have zero width
// (or are misses) can only fit reps with the same values or reps that had a wider interval when they
// joined, so it looks up the former by a hash of its values and scans only the latter: the same
// first fit, at hash-table cost on open meshes, where the scan found nothing to merge.
//
// Input: a tree as produced by build_mh (each block referenced once). Errors: invalid_input for a
// malformed hierarchy or one that already shares blocks. Output: a hierarchy of the same levels
// with shared blocks, unreachable blocks dropped. Thread safety: pure function.
#pragma once

#include <cstdint>

#include "builder/mh_hierarchy.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct MmhMergeOptions {
  unsigned max_tests_per_block = 1024;  // authors' bound
  // Bits of the topology hash used for bucketing (1..64). Test hook: few bits force collisions,
  // which the full structural comparison must reject.
  unsigned hash_bits = 64;
  // Point index (same output, less work): blocks whose intervals are all point-like (zero width, or
  // the miss) are matched through a hash of their values instead of a scan of the bucket; open
  // meshes give nothing else. False: the plain scan, kept as the reference the tests compare with.
  bool index_point_values = true;
};

struct MmhMergeStats {
  uint64_t blocks_before = 0, blocks_after = 0;
  uint64_t merges = 0;            // blocks redirected to a representative
  uint64_t hull_rejections = 0;   // candidates rejected on aggregate bounds
  uint64_t full_tests = 0;        // full structural + interval comparisons
  uint64_t topology_mismatches = 0;  // full tests that found different topology (hash collisions)
};

Result<MhHierarchy> merge_mmh(const MhHierarchy& tree, const MmhMergeOptions& options = {},
                              MmhMergeStats* stats = nullptr);

// True when merge_mmh(tree) provably merges no block (with any options), so its output encodes to
// encode_mh(tree)'s bytes: every block but the root is point-like (all its intervals of zero width,
// or the miss) and no two blocks without branch children have the same mask and values, compared
// by a 64-bit key (equal keys answer false, never a wrong true; blocks that fit have such children
// that fit). Full-depth trees of open meshes under `anywhere` are mostly such tiles. One pass over
// the blocks, a table of recent keys (a tile that merges answers at its first equal neighbours),
// then the structure checks and two bitsets; no copy, table, renumbering or second encode. False
// also for a malformed or shared input.
bool mmh_merge_finds_nothing(const MhHierarchy& tree);

}  // namespace shadowtiles
