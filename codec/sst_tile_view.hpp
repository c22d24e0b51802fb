// Reader of SST tile payloads (format: codec/sst_format.hpp, docs/sst.md): point lookups by Morton
// order descent of a block's quadtree, PCF lit counts over a box, size statistics for `inspect`.
//
// Untrusted input: parse() validates the whole payload up front (header fields, exact section
// sizes, blocks tiling the node section in Morton order, every node's kind, exponent and record
// inside the section, internal nodes only above single texels, child offsets equal to where the
// previous child's subtree ends, dense leaves only at their allowed sides, every stored float
// finite). A payload that passes cannot make a lookup read out of bounds or return a non-finite
// value; anything else is corrupt_data (unsupported for a newer format version). Validation is
// linear in the payload size.
//
// Lifetime: the view does not own the payload bytes; they must outlive it and stay unchanged.
// Thread safety: a parsed view is immutable; lookups may run concurrently. Little-endian hosts only.
#pragma once

#include <cstdint>
#include <span>

#include "common/result.hpp"

namespace shadowtiles {

struct SstStats {
  uint32_t size = 0, block_side = 0, blocks = 0;
  uint64_t payload_bytes = 0, header_bytes = 0, grid_bytes = 0, block_width_bytes = 0;
  uint64_t internal_nodes = 0, internal_bytes = 0;
  uint64_t one_leaves = 0, constant_leaves = 0, plane_leaves = 0, dense_leaves = 0, dense_bytes = 0;
  // Texels covered by each leaf kind (sum = size^2): what the plane fit buys.
  uint64_t one_texels = 0, constant_texels = 0, plane_texels = 0, dense_texels = 0;
};

class SstTileView {
 public:
  SstTileView() = default;

  static Result<SstTileView> parse(std::span<const uint8_t> payload);

  uint32_t size() const { return size_; }
  unsigned levels() const { return levels_; }  // log2(size): level of single texels
  const SstStats& stats() const { return stats_; }

  // Value of texel (u, v). Below full resolution (max_level < levels()) the value of the first
  // texel of (u, v)'s cell at that level: SST nodes hold planes only at leaves, so a coarser map is
  // a decimated one. Preconditions: u, v < size() (asserted; masked in release builds).
  float lookup(uint32_t u, uint32_t v, unsigned max_level = 255) const;

  // Texels of the kw x kh box at (u0, v0) with threshold <= value, at full resolution; equals
  // counting lookup() per texel. Whole leaves are answered at once (a plane by its corners: the
  // decoder's rounded plane is monotone along each axis). Precondition: box inside the tile
  // (asserted; clamped in release).
  uint32_t lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const;

 private:
  struct Box {
    uint32_t x0, y0, x1, y1;  // half-open, tile coordinates
  };
  const uint8_t* block_root(uint32_t bx, uint32_t by, unsigned& width) const;
  uint32_t count_node(const uint8_t* node, unsigned width, uint32_t ox, uint32_t oy, uint32_t side, Box box,
                      float threshold) const;

  const uint8_t* grid_ = nullptr;
  const uint8_t* nodes_ = nullptr;
  uint32_t size_ = 0, block_side_ = 0, block_shift_ = 0, blocks_per_side_ = 0;
  unsigned levels_ = 0;
  SstStats stats_;
};

}  // namespace shadowtiles
