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

// Measured on fzk_haus and oahu (16384², tiles 1024): a BVH build costs about as much per triangle
// reference as this many rays cast and encoded (build stats bvh_thread_sum / refs vs the rest / rays).
inline constexpr double kRayEquivalentsPerTriangleReference = 8.0;
// Measured on fzk_haus 16384², 4 shards (least squares of shard thread-seconds on texels and hit
// texels): a hit texel costs about 4.5 texels more, in the encoders and previews, than a miss.
inline constexpr double kRayEquivalentsPerCoveredTexel = 4.5;

struct TileWork {
  uint64_t morton_index;    // TileLayout::morton_index of the tile
  uint64_t rays;            // texels of the tile
  uint64_t triangle_refs;   // triangles binned to it
  uint64_t covered_texels = 0;  // estimated hit texels (builder/tile_coverage_estimate.hpp)
  double work() const {
    return double(rays) + kRayEquivalentsPerTriangleReference * double(triangle_refs) +
           kRayEquivalentsPerCoveredTexel * double(covered_texels);
  }
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
