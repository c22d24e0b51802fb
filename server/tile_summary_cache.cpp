#include "server/tile_summary_cache.hpp"

#include <spdlog/spdlog.h>

#include "store/lmdb_store.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles::server {
namespace {

Result<TileSummary> load_summary(const ShadowMap& map, store::Method method, TileCoord tile) {
  const store::Store* st = map.local_store();
  if (!st) return make_error(ErrorCode::unsupported, "rendering needs a local store");
  auto snapshot = st->snapshot();
  if (!snapshot) return snapshot.error();
  const uint8_t level = map.layout().tile_level();
  auto key = store::encode_tile_key({method, level, tile.x, tile.y});
  TileSummary summary;
  auto blob = snapshot->get_view(store::Database::tiles, key);
  if (!blob) return blob.error();
  if (!blob->has_value()) {
    for (store::Method other : map.meta().methods) {
      if (other == method) continue;
      auto other_key = store::encode_tile_key({other, level, tile.x, tile.y});
      auto other_blob = snapshot->get_view(store::Database::tiles, other_key);
      if (!other_blob) return other_blob.error();
      if (other_blob->has_value()) {
        summary.kind = TileSummary::Kind::missing;
        return summary;
      }
    }
    summary.kind = TileSummary::Kind::empty;
    return summary;
  }
  summary.blob_bytes = (*blob)->size();
  auto record = snapshot->get_view(store::Database::preview, key);
  if (!record) return record.error();
  if (!record->has_value()) {
    summary.kind = TileSummary::Kind::no_preview;
    return summary;
  }
  auto preview = store::decode_preview(**record, method);
  if (!preview) {
    spdlog::error("preview {}/{}/{}: fails its checks, not drawn: {}", store::method_name(method), tile.x, tile.y,
                  preview.error().message);
    summary.kind = TileSummary::Kind::corrupt;
    return summary;
  }
  if (uint64_t(preview->size) * preview->step != map.layout().tile_size()) {
    spdlog::error("preview {}/{}/{}: covers {} texels, the tile {}", store::method_name(method), tile.x, tile.y,
                  uint64_t(preview->size) * preview->step, map.layout().tile_size());
    summary.kind = TileSummary::Kind::corrupt;
    return summary;
  }
  summary.kind = TileSummary::Kind::stored;
  summary.preview = std::make_shared<const store::TilePreview>(std::move(*preview));
  return summary;
}

}  // namespace

Result<std::shared_ptr<const TileSummary>> TileSummaryCache::get(const ShadowMap& map, store::Method method,
                                                                 TileCoord tile) {
  Key key{map.meta().config_hash, method, tile.x, tile.y};
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(key);
    if (it != entries_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      return it->second.summary;
    }
  }
  // Loaded outside the lock; two threads may load the same tile once each, the first one stays.
  auto loaded = load_summary(map, method, tile);
  if (!loaded) return loaded.error();
  auto summary = std::make_shared<const TileSummary>(std::move(*loaded));
  const size_t bytes = 96 + (summary->preview ? summary->preview->memory_bytes() : 0);
  std::lock_guard lock(mutex_);
  auto [it, inserted] = entries_.try_emplace(key, Entry{summary, bytes, {}});
  if (!inserted) return it->second.summary;
  lru_.push_front(key);
  it->second.lru = lru_.begin();
  bytes_ += bytes;
  while (bytes_ > budget_ && lru_.size() > 1) {
    auto last = entries_.find(lru_.back());
    bytes_ -= last->second.bytes;
    entries_.erase(last);
    lru_.pop_back();
  }
  return summary;
}

size_t TileSummaryCache::bytes() const {
  std::lock_guard lock(mutex_);
  return bytes_;
}

}  // namespace shadowtiles::server
