// LmdbTileSource: a TileSource over a local store directory opened read-only (docs/architecture.md §9:
// MDB_RDONLY | MDB_NOTLS, so any thread of a pool may read). Each call reads in its own LMDB read
// transaction.
// Thread safety: every member may be called concurrently.
#pragma once

#include <filesystem>
#include <memory>

#include "client/tile_source.hpp"
#include "store/lmdb_store.hpp"

namespace shadowtiles {

class LmdbTileSource final : public TileSource {
 public:
  // Errors as store::Store::open (not_found for a directory without a store).
  static Result<std::shared_ptr<LmdbTileSource>> open(const std::filesystem::path& dir);

  Result<std::string> meta_text() const override;
  Result<std::optional<std::vector<uint8_t>>> tile_blob(const store::TileKey& key) const override;
  Result<std::optional<std::vector<uint8_t>>> top_blob(store::Method method) const override;
  std::string describe() const override;

  // The open store, for serving stored blobs unchanged without a copy (server/).
  const store::Store& store() const { return *store_; }

 private:
  explicit LmdbTileSource(std::unique_ptr<store::Store> store) : store_(std::move(store)) {}
  std::unique_ptr<store::Store> store_;
};

}  // namespace shadowtiles
