// Tile encoders: one tile's dual-depth intervals -> the payload of each stored method. The payload
// is what the blob container (store/blob.hpp) compresses and checksums.
// Thread safety: stateless; call concurrently.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "store/method.hpp"
#include "store/result.hpp"

namespace shadowtiles {

// Errors: unsupported for a method this builder cannot encode yet.
Result<std::vector<uint8_t>> encode_tile_payload(store::Method method, const TileIntervals& intervals);
// Methods encode_tile_payload accepts.
bool builder_supports(store::Method method);

}  // namespace shadowtiles
