// Tile encoding: one tile's dual-depth intervals -> the payload of every requested method, through
// the encoder table (builder/method_encoders.hpp); the blob container (store/blob.hpp) compresses and
// checksums it. MH is built once and shared by the methods derived from it (MMH merges it), and the
// tile's root interval is reported for the top levels (docs/architecture.md §5 "tiled build").
// Thread safety: stateless; call concurrently.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/method_encoders.hpp"
#include "common/result.hpp"
#include "store/method.hpp"

namespace shadowtiles {

struct EncodedPayload {
  store::Method method;
  std::vector<uint8_t> payload;
  double seconds = 0;         // this method's own encode time (the shared MH build counts for mh)
  uint64_t reference_bytes = 0;  // SBE16a layout size, for the papers' tables (MH family only)
};

struct TileEncoding {
  std::vector<EncodedPayload> payloads;  // in the order of the requested methods
  DepthInterval root;                    // interval every texel of the tile shares (MH root)
  bool has_root = false;
};

// Errors: unsupported for a method this builder cannot encode; invalid_input for bad intervals.
Result<TileEncoding> encode_tile(const std::vector<store::Method>& methods, const TileIntervals& intervals,
                                 const TileEncodeOptions& options = {});
// Methods encode_tile accepts: those with an available encoder (builder/method_encoders.hpp).
bool builder_supports(store::Method method);

}  // namespace shadowtiles
