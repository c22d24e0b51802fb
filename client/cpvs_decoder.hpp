// CPVS decoder (DESIGN.md §8, seed 004): a tile's voxelized-shadow DAG, answering visibility at
// (u, v, depth). Placeholder until the CPVS baseline lands (issue #7): every payload is refused.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "client/decoded_tile.hpp"

namespace shadowtiles {

// Errors: corrupt_data for a malformed payload; unsupported while the decoder is not built.
Result<std::shared_ptr<const DecodedTile>> decode_cpvs_tile(std::span<const uint8_t> payload);

}  // namespace shadowtiles
