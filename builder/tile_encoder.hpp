// Tile encoders: one tile's dual-depth intervals -> the payload of every requested method (the blob
// container, store/blob.hpp, compresses and checksums it). MH is built once and shared by the
// methods derived from it (MMH merges it), and the tile's root interval is reported for the top
// levels (docs/architecture.md §5 "tiled build").
// Thread safety: stateless; call concurrently.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/mh_builder.hpp"
#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct TileEncodeOptions {
  MhConstruction construction = MhConstruction::bottom_up;
  // Side of the whole map in texels: CPVS quantises depth to this many steps (docs/architecture.md §8).
  uint32_t map_resolution = 0;
};

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
// Methods encode_tile accepts.
bool builder_supports(store::Method method);

}  // namespace shadowtiles
