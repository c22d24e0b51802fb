#include "client/shadow_map.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>

#include "store/blob.hpp"
#include "store/lmdb_store.hpp"

namespace shadowtiles {

Result<std::unique_ptr<ShadowMap>> ShadowMap::open(const std::filesystem::path& store_dir, Options options) {
  auto source = LmdbTileSource::open(store_dir);
  if (!source) return source.error();
  return open(std::shared_ptr<const TileSource>(std::move(*source)), options);
}

Result<std::unique_ptr<ShadowMap>> ShadowMap::open(std::shared_ptr<const TileSource> source, Options options) {
  auto meta_text = source->meta_text();
  if (!meta_text) return meta_text.error();
  auto meta = StoreMeta::parse(*meta_text);
  if (!meta) return meta.error();
  if (!meta->complete)
    return make_error(ErrorCode::invalid_input,
                      source->describe() + " holds an incomplete build: finish it (rerun the same build) first");
  if (meta->methods.empty()) return make_error(ErrorCode::corrupt_data, "meta lists no methods");
  auto frame = meta->light_frame();
  auto layout = meta->layout();
  if (!frame) return frame.error();
  if (!layout) return layout.error();
  // Top trees of hierarchical methods (small: one value per tile at most), checked like any blob.
  std::map<store::Method, std::shared_ptr<const DecodedTile>> top_trees;
  for (store::Method method : meta->methods) {
    auto blob = source->top_blob(method);
    if (!blob) return blob.error();
    if (!blob->has_value()) continue;
    store::BlobHeader header;
    auto payload = store::decode_blob(**blob, &header);
    if (!payload) return make_error(payload.error().code, "top tree: " + payload.error().message);
    if (header.method != method) return make_error(ErrorCode::corrupt_data, "top tree holds another method");
    auto tree = decode_tile(method, *payload);
    if (!tree) return make_error(tree.error().code, "top tree: " + tree.error().message);
    if ((*tree)->size() != layout->tiles_per_side())
      return make_error(ErrorCode::corrupt_data, "top tree size differs from the tile grid");
    top_trees[method] = std::move(*tree);
  }
  auto map = std::unique_ptr<ShadowMap>(new ShadowMap(std::move(source), std::move(*meta), *frame, *layout, options));
  map->top_trees_ = std::move(top_trees);
  return map;
}

namespace {

// The last tile each thread looked up, by map id (ids are never reused, so a destroyed map's entry
// never matches a new map at the same address). Hits here are counted locally and added to the
// shared stats at the next locked lookup.
struct LastTile {
  uint64_t map_id = 0;
  store::TileKey key{};
  std::shared_ptr<const DecodedTile> tile;
  uint64_t unreported_hits = 0;
};
thread_local LastTile t_last_tile;

}  // namespace

uint64_t ShadowMap::next_id() {
  static std::atomic<uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

Result<std::shared_ptr<const DecodedTile>> ShadowMap::tile(store::Method method, TileCoord coord) const {
  if (!meta_.has_method(method))
    return make_error(ErrorCode::unsupported,
                      std::string("method '") + store::method_name(method) + "' is not in this store");
  if (!layout_.contains(coord)) return make_error(ErrorCode::invalid_input, "tile outside the map");
  store::TileKey key{method, layout_.tile_level(), coord.x, coord.y};
  LastTile& last = t_last_tile;
  if (last.map_id == id_ && last.key == key) {
    ++last.unreported_hits;
    return last.tile;
  }
  auto remember = [&](std::shared_ptr<const DecodedTile> tile) {
    last.map_id = id_;
    last.key = key;
    last.tile = tile;
    return tile;
  };
  {
    std::lock_guard lock(cache_mutex_);
    if (last.map_id == id_) stats_.hits += last.unreported_hits;
    last.unreported_hits = 0;
    if (auto it = cache_.find(key); it != cache_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      ++stats_.hits;
      return remember(it->second.tile);
    }
    ++stats_.misses;
  }
  auto blob = source_->tile_blob(key);
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
  if (auto it = cache_.find(key); it != cache_.end()) return remember(it->second.tile);  // raced: keep the first
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
  return remember(decoded);
}

Status ShadowMap::prefetch(store::Method method, std::span<const TileCoord> tiles) const {
  for (TileCoord coord : tiles)
    if (auto decoded = tile(method, coord); !decoded) return decoded.error();
  return {};
}

std::optional<TileCoord> ShadowMap::tile_of(const Vec3& world) const {
  LightSpacePoint light = frame_.to_light(world);
  const double resolution = layout_.resolution();
  if (!(light.u >= 0 && light.u < resolution && light.v >= 0 && light.v < resolution)) return std::nullopt;
  return TileCoord{uint32_t(light.u) / layout_.tile_size(), uint32_t(light.v) / layout_.tile_size()};
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

float ShadowMap::biased_depth(double depth, double bias_world) const {
  // Beyond the far plane nothing lies (the frame keeps every surface a margin short of depth 1), so
  // such a receiver is answered as if on the far plane: lit at misses (stored value 1), shadowed
  // under any surface. Unclamped, its depth would exceed a miss's 1 and read as shadowed.
  return float(std::min(depth, 1.0) - frame_.depth_from_world(bias_world));
}

Result<unsigned> ShadowMap::tile_max_level(std::optional<unsigned> level) const {
  if (!level) return 255u;
  if (*level >= level_count())
    return make_error(ErrorCode::invalid_input, "level must be in [0, " + std::to_string(level_count() - 1) + "]");
  // Levels above the tile level are served by the tile roots until the top levels are stored.
  return *level > layout_.tile_level() ? *level - layout_.tile_level() : 0u;
}

std::optional<float> ShadowMap::top_value(store::Method method, uint32_t u, uint32_t v, unsigned level) const {
  auto it = top_trees_.find(method);
  if (it == top_trees_.end() || level >= layout_.tile_level()) return std::nullopt;
  return it->second->value(u / layout_.tile_size(), v / layout_.tile_size(), level);
}

Result<std::pair<ShadowAnswer, unsigned>> ShadowMap::locate(const Vec3& world, double bias_world,
                                                            std::optional<unsigned> level) const {
  if (Status s = check_query(world, bias_world); !s) return s.error();
  auto max_level = tile_max_level(level);
  if (!max_level) return max_level.error();
  ShadowAnswer answer;
  answer.light = frame_.to_light(world);
  const double resolution = layout_.resolution();
  if (!(answer.light.u >= 0 && answer.light.u < resolution && answer.light.v >= 0 && answer.light.v < resolution)) {
    answer.outside_map = true;
    answer.value = std::numeric_limits<float>::infinity();
  }
  return std::pair{answer, *max_level};
}

Result<double> ShadowMap::query_pcf(const Vec3& world, store::Method method, unsigned kernel,
                                    std::optional<double> bias, std::optional<unsigned> level,
                                    ShadowAnswer* answer_out) const {
  if (kernel == 0 || kernel % 2 == 0 || kernel > kMaxPcfKernel)
    return make_error(ErrorCode::invalid_input,
                      "pcf kernel must be odd and in [1, " + std::to_string(kMaxPcfKernel) + "]");
  double bias_world = bias.value_or(meta_.default_bias);
  auto located = locate(world, bias_world, level);
  if (!located) return located.error();
  auto [answer, max_level] = *located;
  if (answer.outside_map) {
    if (answer_out) *answer_out = answer;
    return 1.0;
  }
  const int64_t cu = int64_t(answer.light.u), cv = int64_t(answer.light.v), half = kernel / 2;
  const float threshold = biased_depth(answer.light.depth, bias_world);
  const int64_t size = layout_.tile_size();
  const int64_t side = int64_t(layout_.resolution());
  // The kernel box, clipped to the map (samples outside are lit), split into its parts per tile.
  const int64_t u_lo = cu - half, u_hi = cu + half, v_lo = cv - half, v_hi = cv + half;
  const int64_t cu_lo = std::max<int64_t>(u_lo, 0), cu_hi = std::min<int64_t>(u_hi, side - 1);
  const int64_t cv_lo = std::max<int64_t>(v_lo, 0), cv_hi = std::min<int64_t>(v_hi, side - 1);
  uint64_t lit = uint64_t(kernel) * kernel - uint64_t(cu_hi - cu_lo + 1) * uint64_t(cv_hi - cv_lo + 1);
  for (int64_t ty = cv_lo / size; ty <= cv_hi / size; ++ty) {
    for (int64_t tx = cu_lo / size; tx <= cu_hi / size; ++tx) {
      auto decoded = tile(method, {uint32_t(tx), uint32_t(ty)});
      if (!decoded) return decoded.error();
      int64_t bu0 = std::max(cu_lo, tx * size), bu1 = std::min(cu_hi, tx * size + size - 1);
      int64_t bv0 = std::max(cv_lo, ty * size), bv1 = std::min(cv_hi, ty * size + size - 1);
      uint32_t kw = uint32_t(bu1 - bu0 + 1), kh = uint32_t(bv1 - bv0 + 1);
      if (!*decoded) {
        lit += uint64_t(kw) * kh;  // empty tile: lit
        continue;
      }
      const DecodedTile& t = **decoded;
      uint32_t lu = uint32_t(bu0 - tx * size), lv = uint32_t(bv0 - ty * size);
      if (max_level == 255) {
        lit += t.lit_count(lu, lv, kw, kh, threshold);
      } else {
        for (uint32_t v = lv; v < lv + kh; ++v)
          for (uint32_t u = lu; u < lu + kw; ++u) {
            auto coarse = top_value(method, uint32_t(tx * size + u), uint32_t(ty * size + v), *level);
            lit += coarse ? threshold <= *coarse : t.lit(u, v, threshold, max_level);
          }
      }
    }
  }
  {
    // The centre texel's value, for the answer's record.
    auto centre = tile(method, {uint32_t(cu / size), uint32_t(cv / size)});
    if (!centre) return centre.error();
    answer.empty_tile = !*centre;
    answer.value = *centre ? (*centre)->value(uint32_t(cu % size), uint32_t(cv % size), max_level)
                           : std::numeric_limits<float>::infinity();
  }
  double fraction = double(lit) / double(kernel * kernel);
  answer.lit = fraction > 0.5;
  if (answer_out) *answer_out = answer;
  return fraction;
}

Result<ShadowAnswer> ShadowMap::query(const Vec3& world, store::Method method, std::optional<double> bias,
                                      std::optional<unsigned> level) const {
  double bias_world = bias.value_or(meta_.default_bias);
  auto located = locate(world, bias_world, level);
  if (!located) return located.error();
  auto [answer, max_level] = *located;
  if (answer.outside_map) return answer;
  uint32_t u = uint32_t(answer.light.u), v = uint32_t(answer.light.v);
  const uint32_t size = layout_.tile_size();
  if (level) {
    if (!meta_.has_method(method))
      return make_error(ErrorCode::unsupported,
                        std::string("method '") + store::method_name(method) + "' is not in this store");
    if (auto coarse = top_value(method, u, v, *level)) {
      answer.value = *coarse;
      answer.lit = biased_depth(answer.light.depth, bias_world) <= answer.value;
      return answer;
    }
  }
  auto decoded = tile(method, {u / size, v / size});
  if (!decoded) return decoded.error();
  if (!*decoded) {
    answer.empty_tile = true;
    answer.value = std::numeric_limits<float>::infinity();
    return answer;
  }
  answer.value = (*decoded)->value(u % size, v % size, max_level);
  // Same comparison as query_pcf, so a 1x1 kernel equals a point query exactly.
  const float threshold = biased_depth(answer.light.depth, bias_world);
  answer.lit = (*decoded)->lit(u % size, v % size, threshold, max_level);
  return answer;
}

CacheStats ShadowMap::cache_stats() const {
  std::lock_guard lock(cache_mutex_);
  CacheStats stats = stats_;
  stats.tiles = cache_.size();
  return stats;
}

}  // namespace shadowtiles
