#include "bench/harness/store_sizes.hpp"

#include <vector>

#include "codec/raw_tile.hpp"
#include "store/blob.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles::bench {

Result<std::map<store::Method, MethodSize>> method_sizes(const ShadowMap& map) {
  std::map<store::Method, MethodSize> sizes;
  bool corrupt = false;
  Status walked = map.local_store()->for_each(store::Database::tiles, {}, [&](auto key, auto value) {
    auto tile_key = store::decode_tile_key(key);
    auto header = store::check_blob(value);
    if (!tile_key || !header) { corrupt = true; return false; }
    MethodSize& s = sizes[tile_key->method];
    ++s.tiles;
    s.blob_bytes += value.size();
    s.payload_bytes += header->raw_size;
    return true;
  });
  if (!walked) return walked.error();
  if (corrupt) return make_error(ErrorCode::corrupt_data, "a tile record fails its checks");
  return sizes;
}

Result<uint64_t> count_nonempty_texels(const ShadowMap& map) {
  if (!map.meta().has_method(store::Method::raw))
    return make_error(ErrorCode::unsupported, "non-empty texels are counted on raw tiles; the store has none");
  // Collect the keys first: decoding inside for_each would hold the read transaction for long.
  std::vector<store::TileKey> keys;
  Status walked = map.local_store()->for_each(store::Database::tiles, {}, [&](auto key, auto) {
    auto tile_key = store::decode_tile_key(key);
    if (tile_key && tile_key->method == store::Method::raw) keys.push_back(*tile_key);
    return true;
  });
  if (!walked) return walked.error();
  uint64_t count = 0;
  for (const store::TileKey& key : keys) {
    auto blob = map.local_store()->get(store::Database::tiles, store::encode_tile_key(key));
    if (!blob) return blob.error();
    if (!blob->has_value()) continue;
    auto payload = store::decode_blob(**blob);
    if (!payload) return payload.error();
    auto view = RawTileView::parse(*payload);
    if (!view) return view.error();
    for (uint32_t v = 0; v < view->size(); ++v)
      for (uint32_t u = 0; u < view->size(); ++u) count += view->value(u, v) < 1.0f;
  }
  return count;
}

}  // namespace shadowtiles::bench
