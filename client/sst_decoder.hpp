// SST decoder (DESIGN.md §8, seed 002): a tile's sparse shadow tree forest of plane-fit quadtrees.
// Placeholder until the SST baseline lands (issue #7): every payload is refused.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "client/decoded_tile.hpp"

namespace shadowtiles {

// Errors: corrupt_data for a malformed payload; unsupported while the decoder is not built.
Result<std::shared_ptr<const DecodedTile>> decode_sst_tile(std::span<const uint8_t> payload);

}  // namespace shadowtiles
