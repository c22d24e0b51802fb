// What a store holds, in one place (docs/architecture.md §9): the LMDB databases, their keys, and
// the codec of the one record that has no header of its own (progress).
//
// | database   | key                                         | value                                   |
// |------------|---------------------------------------------|-----------------------------------------|
// | `meta`     | kMetaBuildKey ("build")                     | JSON build record (codec/store_meta.hpp) |
// |            | kMetaMergeKey ("merge"), while a merge runs | merge marker (builder/shard_merge.cpp)   |
// | `tiles`    | tile key, 10 bytes (store/tile_key.hpp)     | blob (store/blob.hpp)                    |
// | `top`      | top_tree_key(method): "top/<name>"          | blob: the method's top tree + skip list  |
// | `progress` | progress_key(x, y): x u32 BE, y u32 BE      | ProgressRecord, 9 bytes (below)          |
// | `preview`  | tile key                                    | preview record (store/tile_preview.hpp)  |
// | `tileinfo` | tile key                                    | tile info record (store/tile_info.hpp)   |
//
// Database names are in store/lmdb_store.hpp (database_name). All of it is FORMAT.
// Errors: decoders return corrupt_data for a record of the wrong size or with NaN bounds.
// Safe on untrusted input. Thread safety: pure functions.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include "common/result.hpp"
#include "store/method.hpp"

namespace shadowtiles::store {

inline constexpr const char* kMetaBuildKey = "build";  // FORMAT
inline constexpr const char* kMetaMergeKey = "merge";  // FORMAT

// Key of a method's top tree (with embedded skip list) in the `top` database.
inline std::string top_tree_key(Method method) { return std::string("top/") + method_name(method); }

// A committed tile of a build: whether it stored blobs (false: its texels hold no geometry) and
// its root interval, from which the top levels are built, also for tiles of an earlier run.
// FORMAT, 9 bytes: stored u8 (0 or 1), root lower f32 LE, root upper f32 LE (+inf: a miss).
struct ProgressRecord {
  bool stored = false;
  float root_lower = 1.0f;
  float root_upper = std::numeric_limits<float>::infinity();
};
inline constexpr size_t kProgressKeySize = 8;
inline constexpr size_t kProgressRecordSize = 9;

std::array<uint8_t, kProgressKeySize> progress_key(uint32_t tile_x, uint32_t tile_y);
// Errors: corrupt_data for a key that is not 8 bytes.
struct ProgressTile {
  uint32_t x = 0, y = 0;
};
Result<ProgressTile> decode_progress_key(std::span<const uint8_t> key);

std::array<uint8_t, kProgressRecordSize> encode_progress(const ProgressRecord& record);
// Errors: corrupt_data for a wrong size, a stored byte other than 0/1, NaN or inverted bounds.
Result<ProgressRecord> decode_progress(std::span<const uint8_t> value);

}  // namespace shadowtiles::store
