// Min-max hierarchy over a tile's per-texel step bounds (codec/cpvs_format.hpp StepBounds): for any
// square block, the largest lit_end and the smallest shadow_begin of its texels. The CPVS builder
// asks it whether a voxel node is wholly lit-or-free (depth end <= min shadow_begin) or wholly
// shadowed-or-free (depth start >= max lit_end) without visiting the node's texels.
// Texels outside the tile (the cube is wider than the tile when N > T) are free: lit_end 0,
// shadow_begin N. Memory: about T^2 / 2 bytes (blocks of side >= 4 only; smaller ones are read
// from the intervals). Thread safety: immutable after construction.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "codec/cpvs_format.hpp"

namespace shadowtiles {

struct CpvsBlockBounds {
  uint32_t max_lit_end = 0;
  uint32_t min_shadow_begin = 0;
};

class CpvsBoundsPyramid {
 public:
  // Precondition: intervals are valid (no NaN, lower <= upper), tile size a power of two <= depth_steps.
  CpvsBoundsPyramid(const TileIntervals& intervals, uint32_t depth_steps);

  cpvs::StepBounds texel(uint32_t u, uint32_t v) const;
  // Block of side `side` (a power of two) whose corner (u0, v0) is a multiple of side.
  CpvsBlockBounds block(uint32_t side, uint32_t u0, uint32_t v0) const;

 private:
  const TileIntervals& intervals_;
  uint32_t depth_steps_;
  uint32_t base_side_;                              // side of level 0 blocks: min(4, tile size)
  std::vector<std::vector<CpvsBlockBounds>> levels_;  // level i: blocks of side base_side_ << i
};

}  // namespace shadowtiles
