// Random-access view of a CPVS tile payload (codec/cpvs_format.hpp): visibility at (u, v, depth
// step), PCF counts via leaf masks and popcounts, and the first shadowed step of a column.
// parse() checks every header field, every child code and every ref once (refs must land on a node
// start of the next level or on a leaf), so lookups afterwards follow refs without checks.
// Safe on untrusted input: malformed payloads give corrupt_data (unsupported for another version).
// The view points into the payload, which must outlive it. Thread safety: immutable; concurrent
// lookups are fine.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "codec/cpvs_format.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct CpvsParseOptions {
  unsigned max_skip_level = 8;  // deepest level of the skip table (0: none; see skip_ below)
};

class CpvsTileView {
 public:
  struct Stats {
    uint64_t header_bytes = 0;  // header + level table
    uint64_t node_bytes = 0;
    uint64_t leaf_bytes = 0;
    uint64_t nodes = 0;
    uint64_t leaves = 0;
  };

  CpvsTileView() = default;
  static Result<CpvsTileView> parse(std::span<const uint8_t> payload, const CpvsParseOptions& options = {});

  uint32_t size() const { return tile_size_; }
  uint32_t depth_steps() const { return depth_steps_; }
  cpvs::LeafLayout layout() const { return layout_; }
  const Stats& stats() const { return stats_; }
  // Bytes the view holds beside the payload: the skip table (at most an eighth of the payload).
  size_t derived_bytes() const { return skip_.size() * sizeof(uint32_t); }
  unsigned skip_level() const { return skip_level_; }

  // Preconditions for all lookups: u, v < size(); step < depth_steps().
  bool lit_at_step(uint32_t u, uint32_t v, uint32_t step) const;
  // A receiver at biased normalised depth `threshold` (quantised by cpvs::depth_step).
  bool lit(uint32_t u, uint32_t v, float threshold) const;
  // Lit texels of the kw x kh box at (u0, v0) (inside the tile) at the threshold's depth step.
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const;
  // The first shadowed step of column (u, v); depth_steps() when the column is lit throughout.
  uint32_t first_shadowed_step(uint32_t u, uint32_t v) const;

 private:
  struct Box {
    uint32_t u0, v0, u1, v1;  // half-open
  };
  const uint8_t* child_node(unsigned level, const uint8_t* node, uint16_t codes, unsigned child) const;
  uint32_t leaf_ref(unsigned level, const uint8_t* node, uint16_t codes, unsigned child) const;
  uint64_t leaf(uint32_t index) const { return bytes::load_le<uint64_t>(leaves_ + 8 * size_t(index)); }
  uint32_t count_in(unsigned level, const uint8_t* node, uint32_t side, uint32_t nu, uint32_t nv, uint32_t step,
                    const Box& box) const;
  uint32_t first_shadowed_in(unsigned level, const uint8_t* node, uint32_t side, uint32_t z0, uint32_t u,
                             uint32_t v) const;

  // Skip table, derived at parse: for each cell of side 2^skip_shift_ in (u, v, step) (u, v inside
  // the tile), where the descent stands after the top skip_level_ levels: a node's offset in level
  // skip_level_'s region, or kSkipLit / kSkipShadowed when a code above decided the whole cell.
  // Point lookups start there instead of at the root (skip_level_ 0: no table).
  static constexpr uint32_t kSkipLit = 0xFFFFFFFFu, kSkipShadowed = 0xFFFFFFFEu;
  std::vector<uint32_t> skip_;
  unsigned skip_level_ = 0, skip_shift_ = 0;
  uint32_t skip_side_ = 0;  // cells along u and v
  // Entry of the cell holding voxel (u, v, step): depth-major, then v, then u.
  size_t skip_index(uint32_t u, uint32_t v, uint32_t step) const {
    return (size_t(step >> skip_shift_) * skip_side_ + (v >> skip_shift_)) * skip_side_ + (u >> skip_shift_);
  }

  uint32_t tile_size_ = 0;
  uint32_t depth_steps_ = 0;
  cpvs::LeafLayout layout_ = cpvs::LeafLayout::slab8;
  unsigned root_code_ = cpvs::kCodeLit;
  unsigned level_count_ = 0;
  std::vector<const uint8_t*> level_begin_;
  std::vector<uint8_t> ref_width_;
  const uint8_t* leaves_ = nullptr;
  Stats stats_;
};

}  // namespace shadowtiles
