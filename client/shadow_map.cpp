#include "client/shadow_map.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>

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

ShadowMap::ShadowMap(std::shared_ptr<const TileSource> source, StoreMeta meta, LightFrame frame, TileLayout layout,
                     Options options)
    : source_(std::move(source)),
      local_(std::dynamic_pointer_cast<const LmdbTileSource>(source_)),
      meta_(std::move(meta)),
      frame_(frame),
      layout_(layout),
      options_(options),
      tile_shift_(layout.levels_in_tile()),
      id_(next_id()) {
  for (store::Method m : meta_.methods) method_present_[uint8_t(m)] = true;
  for (size_t m = 0; m < bias_floor_.size(); ++m) {
    const double floor = meta_.min_query_bias(store::Method(m));
    bias_floor_[m] = floor > 0 ? floor * (1 - 1e-9) : -std::numeric_limits<double>::infinity();
  }
}

namespace {

// Per-thread pins (see the header): direct-mapped by tile, sized for the map in use (a slot per tile
// of a method, up to kMaxPinSide tiles a side), valid for one map id and one eviction epoch of that
// map. Only the owning thread reads or writes its table. (A fixed 8 x 8 table sent most random
// points over a 16384^2 map in 1024^2 tiles through the locked cache: a quarter of the rate.)
constexpr uint32_t kMinPinSide = 8, kMaxPinSide = 128;  // 64 to 16,384 slots (2 KiB to 512 KiB)
struct alignas(64) TilePins {
  struct Pin {
    uint64_t key = 0;  // packed method/x/y; 0 = unused (method bytes start at 1)
    const DecodedTile* tile = nullptr;
    std::shared_ptr<const DecodedTile> hold;
  };
  uint64_t map_id = 0;
  uint64_t epoch = 0;
  uint64_t unreported_hits = 0;  // added to the shared stats at the next locked lookup
  uint32_t side_bits = 0;        // the table is (1 << side_bits)^2 slots
  std::vector<Pin> pins;
  std::vector<uint32_t> used;  // the slots in use: dropping the pins costs what is pinned
  void drop_all() {
    for (const uint32_t slot : used) pins[slot] = Pin{};
    used.clear();
  }
  // For a map of `tiles_per_side`: a slot per tile up to kMaxPinSide a side (the pins dropped).
  void size_for(uint32_t tiles_per_side) {
    drop_all();
    const uint32_t side = std::clamp(std::bit_ceil(std::max(tiles_per_side, 1u)), kMinPinSide, kMaxPinSide);
    if (pins.size() == size_t(side) * side) return;
    side_bits = uint32_t(std::countr_zero(side));
    pins = std::vector<Pin>(size_t(side) * side);
  }
  ~TilePins();
};
// The raw pointer is what the hot path reads (trivial thread_local: no init guard); the owner
// frees the table at thread exit.
thread_local TilePins* t_pins = nullptr;
thread_local std::unique_ptr<TilePins> t_pins_owner;
TilePins::~TilePins() { t_pins = nullptr; }

TilePins& thread_pins() {
  if (!t_pins) {
    t_pins_owner = std::make_unique<TilePins>();
    t_pins = t_pins_owner.get();
  }
  return *t_pins;
}

inline uint64_t pin_key(store::Method method, uint32_t x, uint32_t y) {
  return (uint64_t(uint8_t(method)) << 56) | (uint64_t(x & 0xfffffff) << 28) | (y & 0xfffffff);
}
// Neighbouring tiles of one method (a block as wide as the table) never collide; methods are spread
// apart.
inline size_t pin_slot(const TilePins& pins, store::Method method, uint32_t x, uint32_t y) {
  const uint32_t side_mask = (1u << pins.side_bits) - 1, slot_mask = (1u << (2 * pins.side_bits)) - 1;
  return ((x & side_mask) | ((y & side_mask) << pins.side_bits)) ^ ((uint32_t(uint8_t(method)) * 341u) & slot_mask);
}

}  // namespace

uint64_t ShadowMap::next_id() {
  static std::atomic<uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

Status ShadowMap::check_bias(store::Method method, double bias_world) const {
  if (!(bias_world < bias_floor_[uint8_t(method)])) return {};
  const double floor = meta_.min_query_bias(method);
  return make_error(ErrorCode::invalid_input,
                    "bias " + std::to_string(bias_world) + " is below " + std::to_string(floor) + ", the least bias " +
                        store::method_name(method) +
                        " answers for in this store (built with an entry slack: docs/receiver-contracts.md)");
}

Status ShadowMap::check_method(store::Method method) const {
  if (method_present_[uint8_t(method)]) return {};
  return make_error(ErrorCode::unsupported,
                    std::string("method '") + store::method_name(method) + "' is not in this store");
}

inline bool ShadowMap::pinned_tile(store::Method method, uint32_t x, uint32_t y, const DecodedTile** tile,
                                   Error* error) const {
  TilePins* pins = t_pins;
  if (pins && pins->map_id == id_ && pins->epoch == epoch_.load(std::memory_order_relaxed)) {
    const TilePins::Pin& pin = pins->pins[pin_slot(*pins, method, x, y)];
    if (pin.key == pin_key(method, x, y)) {
      ++pins->unreported_hits;
      *tile = pin.tile;
      return true;
    }
  }
  return pin_slow(method, x, y, tile, error);
}

bool ShadowMap::pin_slow(store::Method method, uint32_t x, uint32_t y, const DecodedTile** tile,
                         Error* error) const {
  TilePins& pins = thread_pins();
  // Pins of another map or of an older epoch are dropped here, outside any lock.
  uint64_t hits = pins.unreported_hits;
  pins.unreported_hits = 0;
  const uint64_t epoch = epoch_.load(std::memory_order_acquire);
  if (pins.map_id != id_ || pins.epoch != epoch) {
    if (pins.map_id != id_) {
      hits = 0;  // another map's hits
      pins.size_for(layout_.tiles_per_side());
    } else {
      pins.drop_all();
    }
    pins.map_id = id_;
    pins.epoch = epoch;
  }
  auto shared = shared_tile(store::TileKey{method, layout_.tile_level(), x, y}, hits);
  if (!shared) {
    *error = shared.error();
    return false;
  }
  const size_t slot = pin_slot(pins, method, x, y);
  TilePins::Pin& pin = pins.pins[slot];
  if (pin.key == 0) pins.used.push_back(uint32_t(slot));
  pin.key = pin_key(method, x, y);
  pin.tile = shared->get();
  pin.hold = std::move(*shared);
  *tile = pin.tile;
  return true;
}

Result<std::shared_ptr<const DecodedTile>> ShadowMap::shared_tile(const store::TileKey& key,
                                                                  uint64_t reported_hits) const {
  std::unique_lock lock(cache_mutex_);
  stats_.hits += reported_hits;
  ++stats_.locked_lookups;
  bool waited = false;
  for (;;) {
    if (auto it = cache_.find(key); it != cache_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      if (!waited) ++stats_.hits;
      return it->second.tile;
    }
    auto flight = in_flight_.find(key);
    if (flight == in_flight_.end()) break;
    // Another thread is fetching this tile: wait for its result rather than fetch it again.
    std::shared_ptr<InFlight> pending = flight->second;
    if (!waited) ++stats_.shared_misses;
    waited = true;
    fetched_.wait(lock, [&] { return pending->done; });
    if (pending->error) return *pending->error;
    // Loop: normally cached now (unless already evicted again, then this thread fetches it).
  }
  ++stats_.misses;
  auto pending = std::make_shared<InFlight>();
  in_flight_[key] = pending;
  lock.unlock();
  size_t blob_bytes = 0;
  auto decoded = fetch_tile(key, &blob_bytes);
  std::vector<std::shared_ptr<const DecodedTile>> evicted;  // freed after the lock is released
  lock.lock();
  in_flight_.erase(key);
  pending->done = true;
  if (!decoded) {
    pending->error = decoded.error();  // a failed tile is not cached: the next lookup fetches again
    lock.unlock();
    fetched_.notify_all();
    return decoded.error();
  }
  const size_t bytes = *decoded ? (*decoded)->memory_bytes() : 0;
  stats_.fetched_bytes += blob_bytes;
  lru_.push_front(key);
  cache_[key] = CacheEntry{*decoded, bytes, lru_.begin()};
  stats_.bytes += bytes;
  stats_.peak_bytes = std::max(stats_.peak_bytes, stats_.bytes);
  while (stats_.bytes > options_.cache_bytes && lru_.size() > 1) {
    auto victim = cache_.find(lru_.back());
    stats_.bytes -= victim->second.bytes;
    evicted.push_back(std::move(victim->second.tile));
    cache_.erase(victim);
    lru_.pop_back();
    ++stats_.evictions;
  }
  if (!evicted.empty()) epoch_.fetch_add(1, std::memory_order_release);
  lock.unlock();
  fetched_.notify_all();
  return decoded;
}

Result<std::shared_ptr<const DecodedTile>> ShadowMap::fetch_tile(const store::TileKey& key, size_t* blob_bytes) const {
  const store::Method method = key.method;
  auto blob = source_->tile_blob(key);
  if (!blob) return blob.error();
  if (!blob->has_value()) return std::shared_ptr<const DecodedTile>();  // empty tile
  *blob_bytes = (*blob)->size();
  store::BlobHeader header;
  auto payload = store::decode_blob(**blob, &header);
  if (!payload)
    return make_error(payload.error().code, "tile " + std::string(store::method_name(method)) + "/" +
                                                std::to_string(key.x) + "/" + std::to_string(key.y) + ": " +
                                                payload.error().message);
  if (header.method != method) return make_error(ErrorCode::corrupt_data, "tile blob holds another method than its key");
  auto tile = decode_tile(method, *payload);
  if (!tile) return tile.error();
  if ((*tile)->size() != layout_.tile_size())
    return make_error(ErrorCode::corrupt_data, "tile size differs from the store's");
  return tile;
}

Result<std::shared_ptr<const DecodedTile>> ShadowMap::tile(store::Method method, TileCoord coord) const {
  if (Status s = check_method(method); !s) return s.error();
  if (!layout_.contains(coord)) return make_error(ErrorCode::invalid_input, "tile outside the map");
  return shared_tile(store::TileKey{method, layout_.tile_level(), coord.x, coord.y}, 0);
}

Status ShadowMap::prefetch(store::Method method, std::span<const TileCoord> tiles) const {
  if (Status s = check_method(method); !s) return s;
  for (TileCoord coord : tiles) {
    if (!layout_.contains(coord)) return make_error(ErrorCode::invalid_input, "tile outside the map");
    auto decoded = shared_tile(store::TileKey{method, layout_.tile_level(), coord.x, coord.y}, 0);
    if (!decoded) return decoded.error();
  }
  return {};
}

std::optional<TileCoord> ShadowMap::tile_of(const Vec3& world) const {
  LightSpacePoint light = frame_.to_light(world);
  const double resolution = layout_.resolution();
  if (!(light.u >= 0 && light.u < resolution && light.v >= 0 && light.v < resolution)) return std::nullopt;
  return TileCoord{uint32_t(light.u) / layout_.tile_size(), uint32_t(light.v) / layout_.tile_size()};
}

Result<float> ShadowMap::texel_value(store::Method method, uint32_t u, uint32_t v, unsigned max_level) const {
  if (Status s = check_method(method); !s) return s.error();
  if (u >= layout_.resolution() || v >= layout_.resolution())
    return make_error(ErrorCode::invalid_input, "texel outside the map");
  const DecodedTile* decoded;
  Error error;
  if (!pinned_tile(method, u >> tile_shift_, v >> tile_shift_, &decoded, &error)) return error;
  if (!decoded) return std::numeric_limits<float>::infinity();
  const uint32_t mask = layout_.tile_size() - 1;
  return decoded->value(u & mask, v & mask, max_level);
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

[[gnu::always_inline]] inline ShadowAnswer ShadowMap::project(const Vec3& world) const {
  ShadowAnswer answer;
  answer.light = frame_.to_light(world);
  const double resolution = layout_.resolution();
  if (!(answer.light.u >= 0 && answer.light.u < resolution && answer.light.v >= 0 && answer.light.v < resolution))
      [[unlikely]] {
    answer.outside_map = true;
    answer.value = std::numeric_limits<float>::infinity();
  }
  return answer;
}

Result<std::pair<ShadowAnswer, unsigned>> ShadowMap::locate(const Vec3& world, double bias_world,
                                                            std::optional<unsigned> level) const {
  if (Status s = check_query(world, bias_world); !s) return s.error();
  auto max_level = tile_max_level(level);
  if (!max_level) return max_level.error();
  return std::pair{project(world), *max_level};
}

Result<uint64_t> ShadowMap::pcf_lit_samples(store::Method method, int64_t cu, int64_t cv, unsigned kernel,
                                            float threshold, unsigned max_level,
                                            std::optional<unsigned> level) const {
  const int64_t half = kernel / 2;
  const int64_t size = layout_.tile_size();
  const int64_t side = int64_t(layout_.resolution());
  const unsigned shift = tile_shift_;
  if (max_level == 255 && cu - half >= 0 && cv - half >= 0 && cu + half < side && cv + half < side &&
      (cu - half) >> shift == (cu + half) >> shift && (cv - half) >> shift == (cv + half) >> shift) [[likely]] {
    // The common kernel: on the map and inside one tile.
    const DecodedTile* t;
    Error error;
    if (!pinned_tile(method, uint32_t(cu >> shift), uint32_t(cv >> shift), &t, &error)) return error;
    if (!t) return uint64_t(kernel) * kernel;  // empty tile: lit
    const uint32_t mask = uint32_t(size - 1);
    return uint64_t(t->lit_count(uint32_t(cu - half) & mask, uint32_t(cv - half) & mask, kernel, kernel, threshold));
  }
  // The kernel box, clipped to the map (samples outside are lit), split into its parts per tile.
  const int64_t u_lo = cu - half, u_hi = cu + half, v_lo = cv - half, v_hi = cv + half;
  const int64_t cu_lo = std::max<int64_t>(u_lo, 0), cu_hi = std::min<int64_t>(u_hi, side - 1);
  const int64_t cv_lo = std::max<int64_t>(v_lo, 0), cv_hi = std::min<int64_t>(v_hi, side - 1);
  uint64_t lit = uint64_t(kernel) * kernel - uint64_t(cu_hi - cu_lo + 1) * uint64_t(cv_hi - cv_lo + 1);
  for (int64_t ty = cv_lo >> shift; ty <= cv_hi >> shift; ++ty) {
    for (int64_t tx = cu_lo >> shift; tx <= cu_hi >> shift; ++tx) {
      const DecodedTile* t;
      Error error;
      if (!pinned_tile(method, uint32_t(tx), uint32_t(ty), &t, &error)) return error;
      const int64_t bu0 = std::max(cu_lo, tx * size), bu1 = std::min(cu_hi, tx * size + size - 1);
      const int64_t bv0 = std::max(cv_lo, ty * size), bv1 = std::min(cv_hi, ty * size + size - 1);
      const uint32_t kw = uint32_t(bu1 - bu0 + 1), kh = uint32_t(bv1 - bv0 + 1);
      if (!t) {
        lit += uint64_t(kw) * kh;  // empty tile: lit
        continue;
      }
      const uint32_t lu = uint32_t(bu0 - tx * size), lv = uint32_t(bv0 - ty * size);
      if (max_level == 255) {
        lit += t->lit_count(lu, lv, kw, kh, threshold);
      } else {
        for (uint32_t v = lv; v < lv + kh; ++v)
          for (uint32_t u = lu; u < lu + kw; ++u) {
            auto coarse = top_value(method, uint32_t(tx * size + u), uint32_t(ty * size + v), *level);
            lit += coarse ? threshold <= *coarse : t->lit(u, v, threshold, max_level);
          }
      }
    }
  }
  return lit;
}

inline bool ShadowMap::plain_query(const Vec3& world, store::Method method, double bias_world) const {
  const uint8_t m = uint8_t(method);
  return method_present_[m] && !(bias_world < bias_floor_[m]) && bias_world >= 0 && std::isfinite(bias_world) &&
         std::isfinite(world[0]) && std::isfinite(world[1]) && std::isfinite(world[2]);
}

Result<double> ShadowMap::query_pcf(const Vec3& world, store::Method method, unsigned kernel,
                                    std::optional<double> bias, std::optional<unsigned> level,
                                    ShadowAnswer* answer_out) const {
  // As query(): the common call skips the general path's Status and Result values.
  const double bias_world = bias.value_or(meta_.default_bias);
  if (level || kernel % 2 == 0 || kernel > kMaxPcfKernel || !plain_query(world, method, bias_world)) [[unlikely]]
    return query_pcf_general(world, method, kernel, bias_world, level, answer_out);
  ShadowAnswer answer = project(world);
  if (answer.outside_map) [[unlikely]] {
    if (answer_out) *answer_out = answer;
    return 1.0;
  }
  return pcf_fraction(method, kernel, bias_world, 255, std::nullopt, answer, answer_out);
}

Result<double> ShadowMap::query_pcf_general(const Vec3& world, store::Method method, unsigned kernel,
                                            double bias_world, std::optional<unsigned> level,
                                            ShadowAnswer* answer_out) const {
  if (kernel == 0 || kernel % 2 == 0 || kernel > kMaxPcfKernel)
    return make_error(ErrorCode::invalid_input,
                      "pcf kernel must be odd and in [1, " + std::to_string(kMaxPcfKernel) + "]");
  if (Status s = check_method(method); !s) return s.error();
  if (Status s = check_bias(method, bias_world); !s) return s.error();
  auto located = locate(world, bias_world, level);
  if (!located) return located.error();
  auto [answer, max_level] = *located;
  if (answer.outside_map) {
    if (answer_out) *answer_out = answer;
    return 1.0;
  }
  return pcf_fraction(method, kernel, bias_world, max_level, level, answer, answer_out);
}

Result<double> ShadowMap::pcf_fraction(store::Method method, unsigned kernel, double bias_world, unsigned max_level,
                                       std::optional<unsigned> level, ShadowAnswer& answer,
                                       ShadowAnswer* answer_out) const {
  const int64_t cu = int64_t(answer.light.u), cv = int64_t(answer.light.v);
  const float threshold = biased_depth(answer.light.depth, bias_world);
  auto lit = pcf_lit_samples(method, cu, cv, kernel, threshold, max_level, level);
  if (!lit) return lit.error();
  const double fraction = double(*lit) / double(kernel * kernel);
  if (answer_out) {
    // The centre texel's value, for the answer's record (a second descent: only when asked for).
    const DecodedTile* centre;
    Error error;
    if (!pinned_tile(method, uint32_t(cu) >> tile_shift_, uint32_t(cv) >> tile_shift_, &centre, &error)) return error;
    const uint32_t mask = layout_.tile_size() - 1;
    answer.empty_tile = !centre;
    answer.value = centre ? centre->value(uint32_t(cu) & mask, uint32_t(cv) & mask, max_level)
                          : std::numeric_limits<float>::infinity();
    answer.lit = fraction > 0.5;
    *answer_out = answer;
  }
  return fraction;
}

inline bool ShadowMap::sample_tile(store::Method method, double bias_world, unsigned max_level, ShadowAnswer& answer,
                                   Error* error) const {
  const uint32_t u = uint32_t(answer.light.u), v = uint32_t(answer.light.v);
  // Same comparison as query_pcf, so a 1x1 kernel equals a point query exactly.
  const float threshold = biased_depth(answer.light.depth, bias_world);
  const DecodedTile* decoded;
  if (!pinned_tile(method, u >> tile_shift_, v >> tile_shift_, &decoded, error)) return false;
  if (!decoded) {
    answer.empty_tile = true;
    answer.value = std::numeric_limits<float>::infinity();
    return true;
  }
  const uint32_t mask = layout_.tile_size() - 1;
  const DecodedTile::Sample sample = decoded->sample(u & mask, v & mask, threshold, max_level);
  answer.value = sample.value;
  answer.lit = sample.lit;
  return true;
}

Result<ShadowAnswer> ShadowMap::query(const Vec3& world, store::Method method, std::optional<double> bias,
                                      std::optional<unsigned> level) const {
  // The common call (method present, bias and point valid, finest level) without the general
  // path's Status and Result values: those cost as much as a DAG-MH descent per lookup. Any other
  // call takes the general path, which gives the same answers and every error message.
  const double bias_world = bias.value_or(meta_.default_bias);
  if (level || !plain_query(world, method, bias_world)) [[unlikely]]
    return query_general(world, method, bias_world, level);
  ShadowAnswer answer = project(world);
  if (answer.outside_map) [[unlikely]]
    return answer;
  Error error;
  if (!sample_tile(method, bias_world, 255, answer, &error)) [[unlikely]]
    return error;
  return answer;
}

Result<ShadowAnswer> ShadowMap::query_general(const Vec3& world, store::Method method, double bias_world,
                                              std::optional<unsigned> level) const {
  if (Status s = check_method(method); !s) return s.error();
  if (Status s = check_bias(method, bias_world); !s) return s.error();
  auto located = locate(world, bias_world, level);
  if (!located) return located.error();
  auto [answer, max_level] = *located;
  if (answer.outside_map) return answer;
  if (level) {
    const uint32_t u = uint32_t(answer.light.u), v = uint32_t(answer.light.v);
    if (auto coarse = top_value(method, u, v, *level)) {
      answer.value = *coarse;
      answer.lit = biased_depth(answer.light.depth, bias_world) <= answer.value;
      return answer;
    }
  }
  Error error;
  if (!sample_tile(method, bias_world, max_level, answer, &error)) return error;
  return answer;
}

CacheStats ShadowMap::cache_stats() const {
  std::lock_guard lock(cache_mutex_);
  CacheStats stats = stats_;
  stats.tiles = cache_.size();
  return stats;
}

}  // namespace shadowtiles
