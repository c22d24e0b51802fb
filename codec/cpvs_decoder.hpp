// CPVS decoder (docs/architecture.md §8, seed 004): a tile's voxelized-shadow DAG as a DecodedTile, answering
// visibility at (u, v, quantised depth) (lit), PCF by leaf-mask popcounts (lit_count), and as
// value() the start depth of the column's first shadowed step (for reports only). A point query's
// sample() is one descent: its value is the bound of the receiver's depth step that the answer
// proves, not value().
// Errors: corrupt_data for a malformed payload, unsupported for another format version.
// Safe on untrusted input (codec/cpvs_tile_view.hpp validates everything at parse).
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "codec/decoded_tile.hpp"

namespace shadowtiles {

Result<std::shared_ptr<const DecodedTile>> decode_cpvs_tile(std::span<const uint8_t> payload);

}  // namespace shadowtiles
