#include "client/lmdb_tile_source.hpp"

#include "codec/store_meta.hpp"

namespace shadowtiles {

Result<std::shared_ptr<LmdbTileSource>> LmdbTileSource::open(const std::filesystem::path& dir) {
  store::Store::Options options;
  options.mode = store::Store::Mode::read_only;
  auto opened = store::Store::open(dir, options);
  if (!opened) return opened.error();
  return std::shared_ptr<LmdbTileSource>(new LmdbTileSource(std::move(*opened)));
}

Result<std::string> LmdbTileSource::meta_text() const {
  auto raw = store_->get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  if (!raw) return raw.error();
  if (!raw->has_value())
    return make_error(ErrorCode::not_found, store_->path().string() + " holds no build (no meta record)");
  return std::string(reinterpret_cast<const char*>((*raw)->data()), (*raw)->size());
}

Result<std::optional<std::vector<uint8_t>>> LmdbTileSource::tile_blob(const store::TileKey& key) const {
  return store_->get(store::Database::tiles, store::encode_tile_key(key));
}

Result<std::optional<std::vector<uint8_t>>> LmdbTileSource::top_blob(store::Method method) const {
  return store_->get(store::Database::top, store::as_bytes(top_tree_key(method)));
}

std::string LmdbTileSource::describe() const { return "store " + store_->path().string(); }

}  // namespace shadowtiles
