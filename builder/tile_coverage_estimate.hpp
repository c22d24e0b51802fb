// A cheap estimate of how many texels of a tile its triangles cover, for balancing shard plans
// (builder/shard_plan.hpp) before anything is rendered. Under the orthographic light a texel's ray
// hits iff its centre lies inside some triangle's light-space footprint, and the encoders' cost
// follows the hit texels (measured on fzk_haus 16384²: encode + preview thread-seconds per shard
// track hit texels, not texels), so the plan weighs coverage. The footprints are sampled at the
// centres of a kCoverageGrid² grid of cells over the tile; a triangle too small to contain a cell
// centre marks the cell holding its first vertex, so clusters of tiny triangles still count.
// Thread safety: pure; reads the immutable LightSpaceScene.
#pragma once

#include <cstdint>

#include "builder/light_space_scene.hpp"
#include "codec/tile_layout.hpp"

namespace shadowtiles {

inline constexpr uint32_t kCoverageGrid = 32;

// Estimated covered texels of `tile`, in [0, tile_size²]; 0 for a tile without triangles.
uint64_t estimate_covered_texels(const LightSpaceScene& scene, TileCoord tile);

}  // namespace shadowtiles
