#include "codec/tile_layout.hpp"

#include <bit>
#include <string>

namespace shadowtiles {
namespace {

uint64_t spread_bits(uint32_t x) {
  uint64_t v = x;
  v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
  v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
  v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v << 2)) & 0x3333333333333333ull;
  v = (v | (v << 1)) & 0x5555555555555555ull;
  return v;
}

uint32_t gather_bits(uint64_t v) {
  v &= 0x5555555555555555ull;
  v = (v | (v >> 1)) & 0x3333333333333333ull;
  v = (v | (v >> 2)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v >> 4)) & 0x00FF00FF00FF00FFull;
  v = (v | (v >> 8)) & 0x0000FFFF0000FFFFull;
  v = (v | (v >> 16)) & 0x00000000FFFFFFFFull;
  return uint32_t(v);
}

}  // namespace

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

uint64_t TileLayout::morton_index(TileCoord tile) { return spread_bits(tile.x) | (spread_bits(tile.y) << 1); }

TileCoord TileLayout::from_morton_index(uint64_t index) { return {gather_bits(index), gather_bits(index >> 1)}; }

}  // namespace shadowtiles
