// Shard plans (`build --shard I/N`): the map's tiles split into N contiguous ranges of the Morton
// order (neighbouring tiles stay together, so a shard's scene working set stays local), balanced by
// the work each tile holds rather than by tile count: empty tiles cost nothing, and a tile's cost is
// its rays (one per texel), its triangle references (each is BVH-build work) and its estimated hit
// texels (the encoders' work), weighed in ray-equivalents by the constants below. Every shard computes the same plan from
// the same scene and config, so shards agree without talking to each other.
// Errors: parse_shard_spec → invalid_input for anything but "I/N" with 0 <= I < N <= 65536.
// Thread safety: pure functions.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles {

struct ShardSpec {
  uint32_t index = 0;
  uint32_t count = 1;
};
Result<ShardSpec> parse_shard_spec(std::string_view text);

// A tile's work, in ray-equivalents (one ray cast = 1): its rays plus the parts below, weighed by
// shard_plan.cpp's constants (fitted to measured per-tile CPU seconds, docs/scale-out.md).
struct TileWork {
  uint64_t morton_index;    // TileLayout::morton_index of the tile
  uint64_t rays;            // texels of the tile
  uint64_t triangle_refs;   // triangles binned to it
  // The tile's coarse depth map (builder/tile_coverage_estimate.hpp):
  uint64_t covered_texels = 0;  // estimated hit texels
  uint64_t triangle_edges = 0;  // neighbouring cells seeing different triangles
  uint64_t visible_triangles = 0;
  uint64_t sub_cell_triangles = 0;
  uint64_t plane_edges = 0;     // neighbouring cells seeing different planes (creases, steps)
  uint64_t layered_cells = 0;
  double work() const;
};

struct ShardRange {
  uint64_t morton_begin = 0;  // [begin, end) of Morton tile indices
  uint64_t morton_end = 0;
  uint64_t tiles = 0;         // candidate tiles (with triangles) inside
  double work = 0;
};

// `tiles`: candidate tiles in ascending Morton order; `tile_count`: all tiles of the map. The N
// ranges cover [0, tile_count) without overlap. Each tile goes to the shard its work midpoint falls
// in, so every shard is within one tile's work of the ideal share.
std::vector<ShardRange> plan_shards(std::span<const TileWork> tiles, uint64_t tile_count, uint32_t shards);

// max / mean of the ranges' work (1 = perfect); 1 when there is no work.
double shard_imbalance(std::span<const ShardRange> ranges);

}  // namespace shadowtiles
