// A PCF box split at the cells of a tree decoder's skip list, so each part's walk starts from its
// own cell's entry (MhTileView, DagMhTileView). A box that crosses cells (a 3x3 kernel does in ~4 of
// 10 places at level 8) would otherwise walk down from a common ancestor above the list, a step
// per level and, in a deep tree, a cache miss per step.
// Thread safety: a pure function.
#pragma once

#include <algorithm>
#include <cstdint>

namespace shadowtiles {

// Calls part(pu0, pv0, pu1, pv1) for every part of the box [u0, u1] x [v0, v1] (inclusive) inside
// one cell of 2^shift texels a side, cells in row order; returns the sum of what the calls return.
// Always inlined: the callers' ISA clones (common/isa_clones.hpp) keep their instruction set in it.
template <class Part>
[[gnu::always_inline]] inline uint32_t sum_over_skip_cell_parts(uint32_t u0, uint32_t v0, uint32_t u1, uint32_t v1, unsigned shift, Part&& part) {
  uint32_t sum = 0;
  for (uint32_t cv = v0 >> shift; cv <= v1 >> shift; ++cv) {
    const uint32_t pv0 = std::max(v0, cv << shift), pv1 = std::min(v1, ((cv + 1) << shift) - 1);
    for (uint32_t cu = u0 >> shift; cu <= u1 >> shift; ++cu) {
      const uint32_t pu0 = std::max(u0, cu << shift), pu1 = std::min(u1, ((cu + 1) << shift) - 1);
      sum += part(pu0, pv0, pu1, pv1);
    }
  }
  return sum;
}

}  // namespace shadowtiles
