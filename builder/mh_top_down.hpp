// Top-down MH construction (SBE16a Alg. 1), kept to compare with bottom-up (docs/architecture.md §5). Each
// node takes the depth covering the most texel intervals of its region (a sweep over sorted
// endpoints) unless the inherited value covers as many (then it stays empty); quadrants whose
// texels are all covered by the node's value are dropped. Validity intervals are then computed
// from the texels that resolve to each valued node. Only full resolution is guaranteed exact;
// coarse levels are complete maps but need not be exact for any texel.
// Cost: O(n log n) per level. Precondition: check_tile_intervals(tile) passed.
// Thread safety: pure function.
#pragma once

#include "builder/depth_interval.hpp"
#include "builder/mh_hierarchy.hpp"

namespace shadowtiles {

MhHierarchy build_mh_top_down(const TileIntervals& tile);

}  // namespace shadowtiles
