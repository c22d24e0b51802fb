// SST decoder (docs/architecture.md §8, seed 002): a tile's sparse shadow tree forest of plane-fit quadtrees
// (codec/sst_format.hpp) as a DecodedTile: owns the payload, reads it through SstTileView.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "codec/decoded_tile.hpp"

namespace shadowtiles {

// Errors: corrupt_data for a malformed payload; unsupported for a newer format version.
// Safe on untrusted input (the whole payload is validated before the tile is returned).
Result<std::shared_ptr<const DecodedTile>> decode_sst_tile(std::span<const uint8_t> payload);

}  // namespace shadowtiles
