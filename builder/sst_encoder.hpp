// SST encoder (DESIGN.md §8, seed 002): a tile's dual depth -> sparse shadow tree payload.
// Placeholder until the SST baseline lands (issue #7).
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "store/result.hpp"

namespace shadowtiles {

// False while the encoder is a placeholder: the builder then rejects the method up front.
bool sst_encoder_available();
Result<std::vector<uint8_t>> encode_sst_tile(const TileIntervals& intervals);

}  // namespace shadowtiles
