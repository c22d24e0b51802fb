// Internal to the MH builders: a complete quadtree over a tile as dense per-level arrays in Morton
// order (node p at level l has children 4p..4p+3 at level l+1, in the child order of docs/architecture.md §5),
// and its conversion to the block form (MhHierarchy). Breadth-first order of a quadtree level is
// Morton order, so compaction is one sequential pass per level.
// Thread safety: plain functions on caller-owned data.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/mh_hierarchy.hpp"

namespace shadowtiles {

struct MhDenseLevels {
  uint32_t size = 0;
  unsigned levels = 0;
  // masks[l][p], l < levels: 2-bit codes of node p's children (0 for absent or childless nodes).
  std::vector<std::vector<uint8_t>> masks;
  // valued[l]: validity intervals of the valued nodes of level l in Morton order; valued[0] = root.
  std::vector<std::vector<DepthInterval>> valued;
};

// De-interleaves a Morton index into (x, y); x holds the even bits.
inline uint32_t morton_compact(uint64_t m) {
  m &= 0x5555555555555555ull;
  m = (m ^ (m >> 1)) & 0x3333333333333333ull;
  m = (m ^ (m >> 2)) & 0x0f0f0f0f0f0f0f0full;
  m = (m ^ (m >> 4)) & 0x00ff00ff00ff00ffull;
  m = (m ^ (m >> 8)) & 0x0000ffff0000ffffull;
  m = (m ^ (m >> 16)) & 0x00000000ffffffffull;
  return uint32_t(m);
}
inline uint32_t morton_x(uint64_t m) { return morton_compact(m); }
inline uint32_t morton_y(uint64_t m) { return morton_compact(m >> 1); }

// Fills `dense.valued` from `dense.masks`: a valued node's interval is the intersection of the
// texels that resolve to it (whose deepest valued ancestor it is). A valued node no texel resolves
// to is turned into an empty node (its value is never read).
void compute_validity(const TileIntervals& tile, MhDenseLevels& dense);

// Block form, blocks in breadth-first order. Consumes `dense`.
MhHierarchy to_hierarchy(MhDenseLevels&& dense);

}  // namespace shadowtiles
