// A cheap look at what a tile holds, for balancing shard plans (builder/shard_plan.hpp) before
// anything is rendered. Under the orthographic light a texel's ray hits iff its centre lies inside
// some triangle's light-space footprint, and the encoders' cost follows the hit texels (measured on
// fzk_haus 16384²: encode + preview thread-seconds per shard track hit texels, not texels), so the plan
// weighs coverage. The footprints are sampled at the centres of a kCoverageGrid² grid of cells over the
// tile; a triangle too small to contain a cell centre marks the cell holding its first vertex, so
// clusters of tiny triangles still count. The same pass keeps the nearest triangle at each cell centre
// (a coarse depth map with triangle ids), whose complexity is what the per-texel cost follows beyond
// coverage: flat water and terrain (one large triangle over many cells) encode far faster than
// buildings, cranes and aircraft (many visible triangles, depth edges between them).
// Thread safety: pure; reads the immutable LightSpaceScene. Deterministic (the same in every shard
// process): plain double arithmetic in triangle order.
#pragma once

#include <cstdint>

#include "builder/light_space_scene.hpp"
#include "codec/tile_layout.hpp"

namespace shadowtiles {

inline constexpr uint32_t kCoverageGrid = 32;

struct TileFootprint {
  uint64_t covered_texels = 0;      // estimated hit texels, in [0, tile_size²]
  uint64_t covered_cells = 0;       // of kCoverageGrid²
  uint64_t visible_triangles = 0;   // distinct nearest triangles over the cells
  uint64_t triangle_edges = 0;      // neighbouring cell pairs (4-neighbours) seeing different triangles,
                                    // a covered cell beside an empty one included
  uint64_t sub_cell_triangles = 0;  // triangles containing no cell centre (detail below the grid)
  uint64_t plane_edges = 0;         // of those pairs, the ones whose two triangles are not coplanar
                                    // (a crease or a step in depth, not a seam inside a flat polygon)
  uint64_t layered_cells = 0;       // (triangle, cell) pairs: cells covered, counted once per layer
};

// What `tile` holds; all zero for a tile without triangles.
TileFootprint estimate_tile_footprint(const LightSpaceScene& scene, TileCoord tile);

}  // namespace shadowtiles
