// Decoder of DAG-MH tile payloads (format: codec/dagmh_format.hpp, docs/dagmh.md): point lookups at
// full or coarser resolution, PCF over a box inside the tile, size statistics for `inspect`.
//
// Traversal (docs/architecture.md §7): two value indices, `count` (values before the current node in depth-first
// order) and `last` (the deepest value seen on the path); a missing child returns `last`. Treelets are
// checked finest level first; the value index is `count` plus the set bits before the found node.
//
// Untrusted input: parse() validates the whole payload up front (header fields, exact section sizes,
// DAG nodes tiling their section with forward-only references, treelet references in range, every
// stored value count equal to the recomputed one, subtree heights within the level count, the root
// valued, every chunk's layout, size and finiteness). A payload that passes cannot make a lookup read
// out of bounds, loop or return a non-finite value; anything else is corrupt_data (unsupported for a
// newer format version). Validation is linear in the payload size.
//
// Lifetime: the view does not own the payload bytes; they must outlive it and stay unchanged.
// Thread safety: a parsed view is immutable; lookups may run concurrently. Little-endian hosts only.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "codec/texel_query.hpp"
#include "common/result.hpp"

namespace shadowtiles {

inline constexpr unsigned kDagMhAllLevels = std::numeric_limits<unsigned>::max();

struct DagMhParseOptions {
  unsigned skip_level = 6;  // level of the in-memory skip list (clamped to the levels; 0 = none)
};

// Size breakdown (the paper's Tables 3 and 4) and counts.
struct DagMhStats {
  uint32_t size = 0;
  unsigned levels = 0, treelet_height = 0, chunk_size = 0;
  unsigned ref_width = 0, count_width = 0, chunk_offset_width = 0;
  uint64_t payload_bytes = 0;
  uint64_t header_bytes = 0;
  uint64_t dag_bytes = 0, dag_nodes = 0;
  uint64_t dag_mask_bytes = 0, dag_ref_bytes = 0, dag_count_bytes = 0;  // parts of dag_bytes
  uint64_t treelet_bytes = 0, treelets = 0;
  uint64_t chunk_table_bytes = 0;   // chunk offsets
  uint64_t chunk_header_bytes = 0;  // representative, b, bitmap, c_l, c_f (the three below)
  uint64_t representative_bytes = 0;  // f32 representative + u8 b per chunk
  uint64_t bitmap_bytes = 0;          // which values differ from the representative
  uint64_t grid_bytes = 0;            // c_l, c_f of quantised chunks
  uint64_t multiplier_bytes = 0, raw_value_bytes = 0;
  uint64_t values = 0, chunks = 0;
  uint64_t representative_values = 0, quantized_values = 0, raw_values = 0;
};

class DagMhTileView {
 public:
  DagMhTileView() = default;

  static Result<DagMhTileView> parse(std::span<const uint8_t> payload, const DagMhParseOptions& options = {});

  uint32_t size() const { return size_; }
  unsigned levels() const { return levels_; }
  const DagMhStats& stats() const { return stats_; }
  // Bytes the view holds beside the payload: the skip list only (at most an eighth of the payload;
  // treelets and chunk offsets are read in place).
  size_t derived_bytes() const { return skip_.size() * sizeof(State); }

  // Value of texel (u, v) walking at most down to `max_level` (0 = root; levels() or more = full
  // resolution). Preconditions: u, v < size() (asserted; masked in release builds).
  float lookup(uint32_t u, uint32_t v, unsigned max_level = kDagMhAllLevels) const;

  // Lit samples (depth <= value + bias) of the kw x kh box at (u0, v0), full resolution: one descent
  // to the box's lowest common ancestor, then per sample from there. Equals per-sample lookup().
  // Preconditions: box inside the tile (asserted; clamped in release).
  uint32_t pcf_lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float depth, float bias) const;

  // Batch: lit[i] = threshold_i <= lookup(u_i, v_i, max_level); Morton-sorted queries share their
  // descents (each resumes from the deepest node shared with the previous one) and value reads.
  void lit_sorted(std::span<const TexelQuery> queries, unsigned max_level, uint8_t* lit) const;

  // Batch PCF: counts[i] = pcf_lit_count(c.u, c.v, k, k, c.threshold, 0) for the k x k boxes whose
  // lower corners c = corners[i] are sorted along the Morton curve (any order is answered correctly):
  // each box's descent to its common ancestor resumes from the previous box's path. Preconditions
  // as pcf_lit_count's (boxes inside the tile); out-of-contract boxes are answered one by one.
  void pcf_count_sorted(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const;

  // Value number `index` of the depth-first list (< stats().values; masked otherwise).
  float value_at(uint32_t index) const;

 private:
  enum : uint8_t { kDone = 0, kTreelet = 2, kDag = 3 };
  struct State {
    uint32_t ref;    // DAG node offset or treelet index
    uint32_t count;  // index of the first value of the node's subtree
    uint32_t last;   // deepest value index on the path so far
    uint8_t kind;
    uint8_t level;   // level of the DAG node / treelet root
  };
  State root_state() const;
  State start_state(uint32_t u, uint32_t v, unsigned stop) const;
  void step(State& s, uint32_t u, uint32_t v) const;  // DAG node -> child
  uint32_t resolve(State s, uint32_t u, uint32_t v, unsigned stop) const;
  uint32_t treelet_find(const State& s, uint32_t u, uint32_t v, unsigned stop) const;
  bool treelet_bit(const uint8_t* treelet, uint32_t bit, uint32_t* rank) const;
  // The shared part of a PCF box's walks in one treelet: levels 0..split of it (node `node` at
  // `split`) are every sample's, `result` their answer when no deeper level holds a value.
  struct TreeletPrefix {
    unsigned d = 0, split = 0;
    uint32_t node = 0, result = 0;
  };
  TreeletPrefix treelet_prefix(const State& s, uint32_t u, uint32_t v, unsigned lca) const;
  uint32_t treelet_find_below(const State& s, uint32_t u, uint32_t v, const TreeletPrefix& prefix) const;
  uint32_t chunk_of(uint32_t index) const;
  void prefetch_chunk_entry(uint32_t index) const;
  void prefetch_chunk(uint32_t index) const;
  float value_of(uint32_t index) const;  // value_at, inlined into the walks
  // Lit samples of the box [u0, u1] x [v0, v1] from `s`, the walk toward (u0, v0) stopped at or
  // above the box's common ancestor (per sample, resuming from the previous sample's path).
  uint32_t count_from_ancestor(State s, uint32_t u0, uint32_t v0, uint32_t u1, uint32_t v1, float depth,
                               float bias) const;

  const uint8_t* dag_ = nullptr;
  const uint8_t* treelets_ = nullptr;
  const uint8_t* chunk_table_ = nullptr;
  const uint8_t* chunks_ = nullptr;
  uint32_t size_ = 0;
  unsigned levels_ = 0, H_ = 0, wr_ = 0, wc_ = 0, wo_ = 0, chunk_size_ = 1;
  uint8_t chunk_shift_ = 0;  // log2(chunk_size_) when it is a power of two, else 0xff
  size_t treelet_bytes_ = 0;
  uint8_t root_kind_ = 0;
  uint32_t root_ref_ = 0;
  uint32_t value_count_ = 0;
  unsigned skip_level_ = 0;
  std::vector<State> skip_;
  const uint8_t* payload_end_ = nullptr;
  DagMhStats stats_;
};

}  // namespace shadowtiles
