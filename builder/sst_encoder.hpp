// SST encoder (docs/architecture.md §8, seed 002): a tile's dual depth -> sparse shadow tree payload
// (codec/sst_format.hpp, docs/sst.md).
// Per block of min(128, size)^2 texels a quadtree; each node takes the cheapest record that keeps
// every texel of the node inside its interval, tried in order of size: the value 1 (misses), one
// constant, one quantised plane (builder/sst_plane_fit, verified with the decoder's expression);
// otherwise the node is subdivided, or, for nodes of side <= 8 where that is smaller, stores its
// texels' lower bounds densely. Single texels always succeed, so the encoding is lossless.
// Errors: invalid_input for malformed intervals (size not a power of two, NaN, lower > upper,
// non-finite lower) or a payload beyond 32-bit offsets. Thread safety: pure function.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "common/result.hpp"

namespace shadowtiles {

bool sst_encoder_available();
Result<std::vector<uint8_t>> encode_sst_tile(const TileIntervals& intervals);

}  // namespace shadowtiles
