// CPVS encoder (DESIGN.md §8, seed 004): a tile's dual depth -> voxelized-shadow DAG payload.
// Placeholder until the CPVS baseline lands (issue #7).
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "store/result.hpp"

namespace shadowtiles {

// False while the encoder is a placeholder: the builder then rejects the method up front.
bool cpvs_encoder_available();
// `map_resolution`: side of the whole map; depth is quantised to that many steps.
Result<std::vector<uint8_t>> encode_cpvs_tile(const TileIntervals& intervals, uint32_t map_resolution);

}  // namespace shadowtiles
