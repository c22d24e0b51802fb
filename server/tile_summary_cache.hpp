// TileSummaryCache: what the renderer (/v1/render) knows about one tile of one method of the served
// build without decoding it: whether it is stored, empty or missing, its blob size, and its decoded
// preview (store/tile_preview.hpp). An LRU bounded in bytes (previews dominate: 48 KiB each at
// 64²), keyed by build id, method and tile, so a swapped build never sees the old one's entries.
// Kinds: stored (blob and preview), empty (no blob in any method: no geometry), missing (another
// method stores the tile, this one does not: a damaged or partial store), no_preview (blob without
// preview: a store built before previews), corrupt (the preview fails its checks; never drawn as
// data, counted by the caller).
// Errors: the store's read errors (I/O).
// Thread safety: get() may be called concurrently; entries are immutable and shared.
#pragma once

#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>

#include "client/shadow_map.hpp"
#include "store/tile_preview.hpp"

namespace shadowtiles::server {

struct TileSummary {
  enum class Kind { stored, empty, missing, no_preview, corrupt };
  Kind kind = Kind::empty;
  uint64_t blob_bytes = 0;
  std::shared_ptr<const store::TilePreview> preview;  // set when kind == stored
};

class TileSummaryCache {
 public:
  explicit TileSummaryCache(size_t budget_bytes) : budget_(budget_bytes) {}
  Result<std::shared_ptr<const TileSummary>> get(const ShadowMap& map, store::Method method, TileCoord tile);
  size_t bytes() const;

 private:
  using Key = std::tuple<std::string, store::Method, uint32_t, uint32_t>;
  struct Entry {
    std::shared_ptr<const TileSummary> summary;
    size_t bytes;
    std::list<Key>::iterator lru;
  };
  const size_t budget_;
  mutable std::mutex mutex_;
  std::map<Key, Entry> entries_;
  std::list<Key> lru_;  // front = most recent
  size_t bytes_ = 0;
};

}  // namespace shadowtiles::server
