// Builds a tile's preview record (store/tile_preview.hpp) from its dual-depth intervals and the
// method's payload decoded back, so the preview shows what a client decodes, not what the encoder
// meant to store.
// Errors: the decoder's (corrupt_data, unsupported) when the payload does not decode.
// Thread safety: stateless; call concurrently.
#pragma once

#include <span>

#include "builder/depth_interval.hpp"
#include "store/method.hpp"
#include "common/result.hpp"
#include "store/tile_preview.hpp"

namespace shadowtiles {

Result<store::TilePreview> make_tile_preview(const TileIntervals& intervals, store::Method method,
                                             std::span<const uint8_t> payload);

// Whether make_tile_preview reads a payload of method `a` and one of method `b` the same way (MH and
// MMH share a format), so equal payloads give equal previews.
bool previews_decode_alike(store::Method a, store::Method b);

}  // namespace shadowtiles
