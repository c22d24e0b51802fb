#include "client/shadow_map.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "store/blob.hpp"

namespace shadowtiles {

Result<std::unique_ptr<ShadowMap>> ShadowMap::open(const std::filesystem::path& store_dir, Options options) {
  store::Store::Options store_options;
  store_options.mode = store::Store::Mode::read_only;
  auto opened = store::Store::open(store_dir, store_options);
  if (!opened) return opened.error();
  auto raw_meta = (*opened)->get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  if (!raw_meta) return raw_meta.error();
  if (!raw_meta->has_value())
    return make_error(ErrorCode::not_found, store_dir.string() + " holds no build (no meta record)");
  auto meta = StoreMeta::parse(
      std::string_view(reinterpret_cast<const char*>((*raw_meta)->data()), (*raw_meta)->size()));
  if (!meta) return meta.error();
  if (!meta->complete)
    return make_error(ErrorCode::invalid_input,
                      store_dir.string() + " holds an incomplete build: finish it (rerun the same build) first");
  if (meta->methods.empty()) return make_error(ErrorCode::corrupt_data, "meta lists no methods");
  auto frame = meta->light_frame();
  auto layout = meta->layout();
  if (!frame) return frame.error();
  if (!layout) return layout.error();
  return std::unique_ptr<ShadowMap>(
      new ShadowMap(std::move(*opened), std::move(*meta), *frame, *layout, options));
}

Result<std::shared_ptr<const DecodedTile>> ShadowMap::tile(store::Method method, TileCoord coord) const {
  if (!meta_.has_method(method))
    return make_error(ErrorCode::unsupported,
                      std::string("method '") + store::method_name(method) + "' is not in this store");
  if (!layout_.contains(coord)) return make_error(ErrorCode::invalid_input, "tile outside the map");
  store::TileKey key{method, layout_.tile_level(), coord.x, coord.y};
  {
    std::lock_guard lock(cache_mutex_);
    if (auto it = cache_.find(key); it != cache_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      ++stats_.hits;
      return it->second.tile;
    }
    ++stats_.misses;
  }
  auto encoded_key = store::encode_tile_key(key);
  auto blob = store_->get(store::Database::tiles, encoded_key);
  if (!blob) return blob.error();
  std::shared_ptr<const DecodedTile> decoded;
  if (blob->has_value()) {
    store::BlobHeader header;
    auto payload = store::decode_blob(**blob, &header);
    if (!payload)
      return make_error(payload.error().code, "tile " + std::string(store::method_name(method)) + "/" +
                                                  std::to_string(coord.x) + "/" + std::to_string(coord.y) + ": " +
                                                  payload.error().message);
    if (header.method != method)
      return make_error(ErrorCode::corrupt_data, "tile blob holds another method than its key");
    auto tile = decode_tile(method, *payload);
    if (!tile) return tile.error();
    if ((*tile)->size() != layout_.tile_size())
      return make_error(ErrorCode::corrupt_data, "tile size differs from the store's");
    decoded = std::move(*tile);
  }
  std::lock_guard lock(cache_mutex_);
  if (auto it = cache_.find(key); it != cache_.end()) return it->second.tile;  // raced: keep the first
  size_t bytes = decoded ? decoded->memory_bytes() : 0;
  lru_.push_front(key);
  cache_[key] = CacheEntry{decoded, bytes, lru_.begin()};
  stats_.bytes += bytes;
  while (stats_.bytes > options_.cache_bytes && lru_.size() > 1) {
    auto victim = cache_.find(lru_.back());
    stats_.bytes -= victim->second.bytes;
    cache_.erase(victim);
    lru_.pop_back();
  }
  return decoded;
}

Result<float> ShadowMap::texel_value(store::Method method, uint32_t u, uint32_t v, unsigned max_level) const {
  const uint32_t size = layout_.tile_size();
  auto decoded = tile(method, {u / size, v / size});
  if (!decoded) return decoded.error();
  if (!*decoded) return std::numeric_limits<float>::infinity();
  return (*decoded)->value(u % size, v % size, max_level);
}

unsigned ShadowMap::level_count() const { return unsigned(std::countr_zero(layout_.resolution())) + 1; }

namespace {

Status check_query(const Vec3& world, double bias_world) {
  for (double c : world)
    if (!std::isfinite(c)) return make_error(ErrorCode::invalid_input, "point coordinates must be finite");
  if (!std::isfinite(bias_world) || bias_world < 0)
    return make_error(ErrorCode::invalid_input, "bias must be finite and >= 0");
  return {};
}

}  // namespace

Result<unsigned> ShadowMap::tile_max_level(std::optional<unsigned> level) const {
  if (!level) return 255u;
  if (*level >= level_count())
    return make_error(ErrorCode::invalid_input, "level must be in [0, " + std::to_string(level_count() - 1) + "]");
  // Levels above the tile level are served by the tile roots until the top levels are stored.
  return *level > layout_.tile_level() ? *level - layout_.tile_level() : 0u;
}

Result<double> ShadowMap::query_pcf(const Vec3& world, store::Method method, unsigned kernel,
                                    std::optional<double> bias, std::optional<unsigned> level,
                                    ShadowAnswer* answer_out) const {
  if (kernel == 0 || kernel % 2 == 0 || kernel > kMaxPcfKernel)
    return make_error(ErrorCode::invalid_input,
                      "pcf kernel must be odd and in [1, " + std::to_string(kMaxPcfKernel) + "]");
  double bias_world = bias.value_or(meta_.default_bias);
  if (Status s = check_query(world, bias_world); !s) return s.error();
  auto max_level = tile_max_level(level);
  if (!max_level) return max_level.error();
  ShadowAnswer answer;
  answer.light = frame_.to_light(world);
  const double resolution = layout_.resolution();
  if (!(answer.light.u >= 0 && answer.light.u < resolution && answer.light.v >= 0 && answer.light.v < resolution)) {
    answer.outside_map = true;
    answer.value = std::numeric_limits<float>::infinity();
    if (answer_out) *answer_out = answer;
    return 1.0;
  }
  const int64_t cu = int64_t(answer.light.u), cv = int64_t(answer.light.v), half = kernel / 2;
  const double threshold = answer.light.depth - frame_.depth_from_world(bias_world);
  const uint32_t size = layout_.tile_size();
  const int64_t side = int64_t(layout_.resolution());
  uint64_t lit = 0;
  // Samples grouped by tile: each tile is fetched once per kernel.
  for (int64_t v = cv - half; v <= cv + half; ++v) {
    for (int64_t u = cu - half; u <= cu + half;) {
      if (u < 0 || v < 0 || u >= side || v >= side) { ++lit; ++u; continue; }
      TileCoord coord{uint32_t(u / size), uint32_t(v / size)};
      int64_t run_end = std::min<int64_t>(cu + half, int64_t(coord.x + 1) * size - 1);
      auto decoded = tile(method, coord);
      if (!decoded) return decoded.error();
      for (; u <= run_end; ++u) {
        float value = *decoded ? (*decoded)->value(uint32_t(u) % size, uint32_t(v) % size, *max_level)
                               : std::numeric_limits<float>::infinity();
        if (u == cu && v == cv) {
          answer.value = value;
          answer.empty_tile = !*decoded;
        }
        lit += threshold <= double(value);
      }
    }
  }
  double fraction = double(lit) / double(kernel * kernel);
  answer.lit = fraction > 0.5;
  if (answer_out) *answer_out = answer;
  return fraction;
}

Result<ShadowAnswer> ShadowMap::query(const Vec3& world, store::Method method, std::optional<double> bias,
                                      std::optional<unsigned> level) const {
  double bias_world = bias.value_or(meta_.default_bias);
  if (Status s = check_query(world, bias_world); !s) return s.error();
  auto max_level = tile_max_level(level);
  if (!max_level) return max_level.error();
  ShadowAnswer answer;
  answer.light = frame_.to_light(world);
  const double resolution = layout_.resolution();
  if (!(answer.light.u >= 0 && answer.light.u < resolution && answer.light.v >= 0 && answer.light.v < resolution)) {
    answer.outside_map = true;
    answer.value = std::numeric_limits<float>::infinity();
    return answer;
  }
  uint32_t u = uint32_t(answer.light.u), v = uint32_t(answer.light.v);
  const uint32_t size = layout_.tile_size();
  auto decoded = tile(method, {u / size, v / size});
  if (!decoded) return decoded.error();
  if (!*decoded) {
    answer.empty_tile = true;
    answer.value = std::numeric_limits<float>::infinity();
    return answer;
  }
  answer.value = (*decoded)->value(u % size, v % size, *max_level);
  // Same comparison as query_pcf, so a 1x1 kernel equals a point query exactly.
  answer.lit = answer.light.depth - frame_.depth_from_world(bias_world) <= double(answer.value);
  return answer;
}

CacheStats ShadowMap::cache_stats() const {
  std::lock_guard lock(cache_mutex_);
  CacheStats stats = stats_;
  stats.tiles = cache_.size();
  return stats;
}

}  // namespace shadowtiles
