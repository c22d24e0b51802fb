// Decoder of MH / MMH tile payloads (format: codec/mh_format.hpp, docs/mh.md): point lookups at
// full or coarser resolution, PCF over a kernel inside the tile, statistics for `inspect`.
//
// Untrusted input: parse() validates the whole payload up front (header, every reachable block
// inside the stream, blocks tiling the stream exactly, forward-only offsets, depth bounded by the
// level count, finite values, header counts, embedded skip list equal to the derived one). A payload
// that passes cannot make a lookup read out of bounds or loop; anything else is corrupt_data.
// Validation is linear in the payload size (plus a sort of the block references).
//
// Lifetime: MhTileView does not own the payload bytes; they must outlive the view and stay
// unchanged. Thread safety: a parsed view is immutable; any number of threads may look up
// concurrently. Requires a little-endian host (checked at compile time).
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "codec/texel_query.hpp"
#include "common/result.hpp"

namespace shadowtiles {

inline constexpr unsigned kMhAllLevels = std::numeric_limits<unsigned>::max();
// MhParseOptions::skip_level: chosen from the payload's size (see there).
inline constexpr unsigned kMhSkipLevelBySize = std::numeric_limits<unsigned>::max();

struct MhParseOptions {
  // Level of the in-memory skip list lookups start from; clamped to the tile's levels, 0 = none.
  // kMhSkipLevelBySize: the deepest level (at most 10) whose entries take at most a fifth of the
  // payload, so a decoded tile stays within 1.2x its payload while a large, deep tile (a full-depth
  // tree of an open mesh under `anywhere`: 14 MB at 2048^2) starts its walks at level 8 or 9, two
  // or three blocks above its texels, instead of five. A compact tile (~80 KB) gets level 5, one
  // step more than the former fixed level 6, whose 48 KiB were not counted and made such tiles ~1.6x
  // their payload. Ignored when the payload embeds a skip list (that one is validated and used).
  unsigned skip_level = kMhSkipLevelBySize;
};

// Counts over the stored (distinct) nodes; the root counts as a leaf or inner node.
struct MhStats {
  uint32_t size = 0;
  unsigned levels = 0;
  bool merged = false;          // payload flagged as MMH (shared blocks allowed)
  unsigned offset_width = 0;    // bytes per block offset
  unsigned skip_level = 0;      // embedded skip list level (0: none)
  uint64_t payload_bytes = 0;   // header + skip list + node stream
  uint64_t header_bytes = 0;
  uint64_t skip_list_bytes = 0;
  uint64_t stream_bytes = 0;
  uint64_t blocks = 0;          // distinct child blocks
  uint64_t inner_nodes = 0;     // value + children
  uint64_t empty_nodes = 0;     // children only
  uint64_t leaf_nodes = 0;      // value only
  uint64_t block_references = 0;  // records pointing at blocks; > blocks - 1 when blocks are shared
  uint64_t nodes() const { return inner_nodes + empty_nodes + leaf_nodes; }
};

class MhTileView {
 public:
  MhTileView() = default;

  // Validates `payload` completely (see above). Errors: corrupt_data for any malformed, truncated
  // or inconsistent payload; unsupported for a newer format version.
  static Result<MhTileView> parse(std::span<const uint8_t> payload, const MhParseOptions& options = {});

  uint32_t size() const { return size_; }
  unsigned levels() const { return levels_; }
  float root_value() const { return root_value_; }
  const MhStats& stats() const { return stats_; }
  // Level of the in-memory skip list (0: none), and the bytes it holds beside the payload.
  unsigned skip_level() const { return skip_level_; }
  size_t derived_bytes() const { return skip_.size() * sizeof(WalkState); }

  // Shadow value for texel (u, v): the value of the deepest valued node on the path, walking at most
  // down to level `max_level` (0 = root only; levels() or more = full resolution). Every level is a
  // complete shadow map. Preconditions: u, v < size() (asserted; in release builds they are masked
  // into the tile, never read out of bounds).
  float lookup(uint32_t u, uint32_t v, unsigned max_level = kMhAllLevels) const;

  // Fraction of the k x k texels [u0, u0+k) x [v0, v0+k) that are lit for a receiver at `depth`
  // (lit: depth <= value + bias), at full resolution. Descends once to the kernel's lowest common
  // ancestor, then per sample (by their parents' 2x2 squares) from the deepest node shared with the
  // previous sample. Equal to the per-sample lookup() result. Preconditions: k >= 1,
  // u0 + k <= size(), v0 + k <= size() (kernels crossing tiles are split by the caller); violations
  // are asserted and clamped in release.
  float pcf_lit_fraction(uint32_t u0, uint32_t v0, uint32_t k, float depth, float bias) const;

  // Lit-sample count for the same kernel (pcf_lit_fraction = count / k^2), for callers that split a
  // kernel across tiles.
  uint32_t pcf_lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float depth, float bias) const;

  // Batch: lit[i] = threshold_i <= lookup(u_i, v_i, max_level). Queries sorted along the Morton
  // curve share their descents: each resumes from the deepest node shared with the previous one.
  // Sparse queries (few neighbours sharing a deep node: a batch spread over a deep tree) are walked
  // independently instead, 8 at a time in turn with a prefetch of each next block, so their cache
  // misses overlap. Preconditions as lookup().
  void lit_sorted(std::span<const TexelQuery> queries, unsigned max_level, uint8_t* lit) const;

  // Batch PCF: counts[i] = pcf_lit_count(c.u, c.v, k, k, c.threshold, 0) for k x k boxes with lower
  // corners c = corners[i]. Boxes sorted along the Morton curve share their descents to the boxes'
  // common ancestors (each resumes from the deepest node shared with the previous corner); any order
  // is answered correctly. Preconditions as pcf_lit_count().
  void pcf_count_sorted(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const;

 private:
  struct WalkState {
    float value;
    uint32_t offset;  // child block of the node, valid when mask != 0
    uint8_t mask;     // codes of the node's children; 0 = walk ends here
  };
  template <unsigned W>
  uint32_t count_from_ancestor(WalkState s, unsigned lca, uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh,
                               float depth, float bias) const;
  template <unsigned W>
  void pcf_count_sorted_impl(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const;
  template <unsigned W>
  uint32_t pcf_count_impl(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float depth, float bias) const;
  template <unsigned W>
  void lit_sorted_impl(std::span<const TexelQuery> queries, unsigned stop, uint8_t* lit) const;
  template <unsigned W>
  void lit_interleaved_impl(std::span<const TexelQuery> queries, unsigned stop, uint8_t* lit) const;
  bool sparse_queries(std::span<const TexelQuery> queries, unsigned stop) const;
  WalkState start_state(uint32_t u, uint32_t v, unsigned max_level, unsigned* level) const;
  // Entry of skip_ holding texel (u, v) (skip_level_ > 0).
  size_t skip_index(uint32_t u, uint32_t v) const {
    const unsigned shift = levels_ - skip_level_;
    return (size_t(v >> shift) << skip_level_) | (u >> shift);
  }

  const uint8_t* stream_ = nullptr;
  uint32_t size_ = 0;
  unsigned levels_ = 0;
  unsigned offset_width_ = 0;
  float root_value_ = 0;
  uint8_t root_mask_ = 0;
  uint32_t root_block_ = 0;
  unsigned skip_level_ = 0;        // level of skip_ (0: no skip list)
  std::vector<WalkState> skip_;    // 4^skip_level_ entries, row-major
  MhStats stats_;
};

}  // namespace shadowtiles
