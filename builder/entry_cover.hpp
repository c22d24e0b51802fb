// The `surfaces` contract's entry rule (docs/receiver-contracts.md, "The entry rule") for one tile:
// per hit texel, a cover of its square by triangles (the first-hit triangle, grown across shared
// edges) and the bound min(first hit, the cover's largest depth over the square + tolerance - slack),
// rounded up. The renderer feeds it row by row, a band of rows after their rays.
// Thread safety: one instance per tile and thread (it caches the last triangle's edge lines).
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/tile_geometry.hpp"
#include "common/float_rounding.hpp"

namespace shadowtiles {

// min(lower, deepest + tolerance - slack), rounded up to a float and one float step more: never
// below the exact bound, nor below verify's reference (builder/reference_entry_bounds.hpp), which
// evaluates the same planes another way. `lower` when that is not smaller. Inline, with selects for
// branches: the entry pass takes it for most hit texels, and which way it goes varies texel by texel.
inline float entry_bound(double deepest, float lower, float slack, float tolerance) {
  const double entry = deepest + double(tolerance) - double(slack);
  const float bound = std::clamp(next_float_up(float_at_least(entry)), 0.0f, lower);
  return entry >= double(lower) ? lower : bound;
}

class EntryCover {
 public:
  // `slack`, `tolerance`: DualDepthOptions::entry_slack and entry_tolerance (normalised depth).
  EntryCover(const TileGeometry& geometry, TileCoord tile, uint32_t tile_size,
             float slack, float tolerance);
  ~EntryCover();
  EntryCover(const EntryCover&) = delete;
  EntryCover& operator=(const EntryCover&) = delete;

  // A first hit as the renderer records it per texel: the triangle, with this flag when it is in the
  // open set.
  static constexpr uint32_t kOpenFlag = 1u << 31;

  // The bound of every hit texel (lower < 1) of tile row v into entry_lower (the others untouched):
  // for texel u, whose centre ray first hit `first_hits[u]` (prim | kOpenFlag when open) at depth
  // row[u].lower, that depth itself when no cover is found. A run of texels with one first hit at a
  // time.
  void bound_row(uint32_t v, std::span<const uint32_t> first_hits, std::span<const DepthInterval> row,
                 std::span<float> entry_lower);

 private:
  class Fast;
  // Asks the cache for a triangle's vertices, plane and neighbours (a search reads all three).
  void prefetch_triangle(bool open, uint32_t prim) const;

  const TileGeometry& geometry_;
  double tile_u0_, tile_v0_;
  float slack_, tolerance_;
  std::unique_ptr<Fast> fast_;
  std::vector<double> run_deepest_;  // bound_row's per-run scratch
  struct Search {
    uint32_t u, key;  // a texel of the row that needs entry_lower_by_search, and its first hit
  };
  std::vector<Search> searches_;  // bound_row's, in u order
};

}  // namespace shadowtiles
