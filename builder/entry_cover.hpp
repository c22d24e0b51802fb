// The `surfaces` contract's entry rule (docs/receiver-contracts.md, "The entry rule") for one tile:
// per hit texel, a cover of its square by triangles (the first-hit triangle, grown across shared
// edges) and the bound min(first hit, the cover's largest depth over the square + tolerance - slack),
// rounded up. The renderer feeds it row by row after the row's rays.
// Thread safety: one instance per tile and thread (it caches the last triangle's edge lines).
#pragma once

#include <cstdint>
#include <memory>

#include "builder/light_space_scene.hpp"
#include "builder/tile_geometry.hpp"

namespace shadowtiles {

// min(lower, deepest + tolerance - slack), rounded up to a float and one float step more: never
// below the exact bound, nor below verify's reference (builder/reference_entry_bounds.hpp), which
// evaluates the same planes another way. `lower` when that is not smaller.
float entry_bound(double deepest, float lower, float slack, float tolerance);

class EntryCover {
 public:
  // `slack`, `tolerance`: DualDepthOptions::entry_slack and entry_tolerance (normalised depth).
  EntryCover(const TileGeometry& geometry, TileCoord tile, uint32_t tile_size,
             float slack, float tolerance);
  ~EntryCover();
  EntryCover(const EntryCover&) = delete;
  EntryCover& operator=(const EntryCover&) = delete;

  // The bound of texel (u, v) (tile-local) whose centre ray first hit triangle `prim` (of the open
  // set when `open`) at depth `lower` (< 1); `lower` itself when no cover is found.
  float bound(bool open, uint32_t prim, uint32_t u, uint32_t v, float lower);

 private:
  class Fast;
  const TileGeometry& geometry_;
  double tile_u0_, tile_v0_;
  float slack_, tolerance_;
  std::unique_ptr<Fast> fast_;
};

}  // namespace shadowtiles
