// TileLayout: how an R x R shadow map is cut into T x T tiles (docs/architecture.md §3).
// Tiles are addressed (x, y) on the grid of the tile level L = log2(R / T) (2^L tiles per side), the
// same scheme the HTTP tile URLs use. Thread safety: immutable value type.
#pragma once

#include <cstdint>

#include "common/result.hpp"

namespace shadowtiles {

struct TileCoord {
  uint32_t x = 0;
  uint32_t y = 0;
  auto operator<=>(const TileCoord&) const = default;
};

class TileLayout {
 public:
  // Errors: resolution or tile size not a power of two; the tile is clamped to the map when larger
  // (a tile larger than the map is simply the whole map).
  static Result<TileLayout> make(uint32_t resolution, uint32_t tile_size);

  uint32_t resolution() const { return resolution_; }
  uint32_t tile_size() const { return tile_size_; }
  uint32_t tiles_per_side() const { return resolution_ / tile_size_; }
  uint64_t tile_count() const { return uint64_t(tiles_per_side()) * tiles_per_side(); }
  uint8_t tile_level() const { return tile_level_; }      // log2(tiles_per_side)
  uint8_t levels_in_tile() const { return levels_in_tile_; } // log2(tile_size)
  bool contains(TileCoord tile) const { return tile.x < tiles_per_side() && tile.y < tiles_per_side(); }
  // Tile ordinal along the Morton (Z-order) curve: contiguous ranges are compact regions, which
  // keeps shards and LMDB key ranges local.
  static uint64_t morton_index(TileCoord tile);
  static TileCoord from_morton_index(uint64_t index);

 private:
  uint32_t resolution_ = 1;
  uint32_t tile_size_ = 1;
  uint8_t tile_level_ = 0;
  uint8_t levels_in_tile_ = 0;
};

}  // namespace shadowtiles
