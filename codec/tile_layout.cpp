#include "codec/tile_layout.hpp"

#include <bit>
#include <string>

#include "codec/morton.hpp"

namespace shadowtiles {

Result<TileLayout> TileLayout::make(uint32_t resolution, uint32_t tile_size) {
  if (!std::has_single_bit(resolution))
    return make_error(ErrorCode::invalid_input, "resolution must be a power of two, got " + std::to_string(resolution));
  if (!std::has_single_bit(tile_size))
    return make_error(ErrorCode::invalid_input, "tile size must be a power of two, got " + std::to_string(tile_size));
  TileLayout layout;
  layout.resolution_ = resolution;
  layout.tile_size_ = tile_size > resolution ? resolution : tile_size;
  layout.tile_level_ = uint8_t(std::countr_zero(layout.tiles_per_side()));
  layout.levels_in_tile_ = uint8_t(std::countr_zero(layout.tile_size_));
  return layout;
}

uint64_t TileLayout::morton_index(TileCoord tile) { return morton_spread(tile.x) | (morton_spread(tile.y) << 1); }

TileCoord TileLayout::from_morton_index(uint64_t index) { return {morton_compact(index), morton_compact(index >> 1)}; }

}  // namespace shadowtiles
