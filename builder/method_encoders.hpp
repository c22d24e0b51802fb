// The encoder table (docs/architecture.md §15): method byte → how the builder encodes a tile, and,
// for methods with a top tree, the tree over the tiles' root intervals. One line per built-in method
// in method_encoders.cpp; extensions and tests add theirs with register_encoder.
// Thread safety: lookups are safe concurrently; register_encoder() must happen before any
// concurrent use. Encoders themselves are stateless and run concurrently on different tiles.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_hierarchy.hpp"
#include "common/result.hpp"
#include "store/method.hpp"

namespace shadowtiles {

struct TileEncodeOptions {
  MhConstruction construction = MhConstruction::bottom_up;
  // Side of the whole map in texels: CPVS quantises depth to this many steps (docs/architecture.md §8).
  uint32_t map_resolution = 0;
};

struct EncodedBytes {
  std::vector<uint8_t> payload;
  uint64_t reference_bytes = 0;  // SBE16a layout size, for the papers' tables (MH family only)
};

// One tile's input to every encoder. The tile's MH is built once, on first demand, and shared by
// the methods derived from it (MMH merges it, DAG-MH encodes it).
class TileEncodeInput {
 public:
  TileEncodeInput(const TileIntervals& intervals, const TileEncodeOptions& options)
      : intervals_(intervals), options_(options) {}
  // The rendered intervals: lower is the first hit (raw and SST store it).
  const TileIntervals& intervals() const { return intervals_; }
  // The intervals CPVS encodes: with the entry rule's bounds applied when the renderer made them (a
  // copy, made once), else intervals(). The MH family needs no copy: build_mh applies the bounds.
  const TileIntervals& interval_method_intervals();
  const TileEncodeOptions& options() const { return options_; }
  // Errors: those of build_mh.
  Result<const MhHierarchy*> mh();
  bool mh_built() const { return mh_.has_value(); }
  // encode_mh(*mh()) and its reference size, made once: MH's encoding, and MMH's too where its
  // merge provably finds nothing (mmh_merge_finds_nothing). Errors: those of mh() and encode_mh.
  Result<const EncodedBytes*> mh_encoded();

 private:
  const TileIntervals& intervals_;
  const TileEncodeOptions& options_;
  std::optional<TileIntervals> entry_applied_;
  std::optional<MhHierarchy> mh_;
  std::optional<EncodedBytes> mh_encoded_;
};

struct MethodEncoder {
  Result<EncodedBytes> (*encode)(TileEncodeInput& input) = nullptr;
  // Whether this build of the builder can encode the method; nullptr: always.
  bool (*available)() = nullptr;
  // The top tree over the tiles' root intervals (one texel per tile), with its skip list down to
  // `skip_level`; set exactly for methods whose properties say has_top_tree.
  Result<std::vector<uint8_t>> (*encode_top_tree)(const TileIntervals& roots, unsigned skip_level) = nullptr;
};

// The encoder of `method`, or nullptr when the builder has none.
const MethodEncoder* find_encoder(store::Method method);

// Errors: invalid_input when the method is not registered in store/method.hpp, already has an
// encoder, or has no encode function.
Status register_encoder(store::Method method, const MethodEncoder& encoder);

}  // namespace shadowtiles
