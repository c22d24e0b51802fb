// The decoder table (docs/architecture.md §15): method byte → the function that turns a blob's
// payload into a DecodedTile. One line per built-in method in method_decoders.cpp; extensions and
// tests add theirs with register_decoder. decode_tile (codec/decoded_tile.hpp) dispatches through it.
// Thread safety: lookups are safe concurrently; register_decoder() must happen before any
// concurrent use.
#pragma once

#include <memory>
#include <span>

#include "codec/decoded_tile.hpp"
#include "common/result.hpp"
#include "store/method.hpp"

namespace shadowtiles {

// Must be safe on untrusted input: corrupt_data for a malformed payload, unsupported for a format
// version it does not read.
using TileDecoder = Result<std::shared_ptr<const DecodedTile>> (*)(std::span<const uint8_t> payload);

// The decoder of `method`, or nullptr when this library has none.
TileDecoder find_decoder(store::Method method);

// Errors: invalid_input when the method is not registered in store/method.hpp or already has one.
Status register_decoder(store::Method method, TileDecoder decoder);

}  // namespace shadowtiles
