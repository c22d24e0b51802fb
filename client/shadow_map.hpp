// ShadowMap: answers "is this world point lit?" from a build (docs/architecture.md §3): world point ->
// light space (u, v, depth) -> tile -> decoded value; lit when min(depth, 1) <= value + bias (points
// beyond the far plane answer as on it: no surface reaches depth 1, see LightFrame::fit).
// Tiles are read from a TileSource (a local LMDB store, or a server over HTTP), checked (header,
// checksum, method) and decoded on demand and kept in an LRU cache bounded in bytes. A tile that
// fails its checks is an error, never an answer.
// Points outside the map are lit and flagged; absent tiles of a complete build are empty (lit).
// Thread safety: all methods may be called concurrently. Lookups scale with threads: a lookup's
// hot path writes nothing shared (no reference count, atomic or lock). Eviction safety is by
// per-thread pins: each thread keeps shared_ptr pins to the tiles it used last (direct-mapped, a
// slot per tile of the map up to 128 x 128 tiles of a method), reads them by raw pointer, and
// re-pins through the locked shared cache on a miss.
// The cache evicts only its own reference; an evicted tile lives on until every thread that pinned
// it notices the cache's eviction epoch changed (at its next lookup) and drops its pins, or exits.
// So the cache may exceed its budget by the tiles pinned by threads between an eviction and their
// next lookup. Concurrent misses on one tile fetch and decode it once (the others wait for it).
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include <span>

#include "codec/decoded_tile.hpp"
#include "client/lmdb_tile_source.hpp"
#include "codec/store_meta.hpp"
#include "client/tile_source.hpp"
#include "common/huge_page_array.hpp"
#include "store/lmdb_store.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles {

struct ShadowAnswer {
  bool lit = true;
  bool outside_map = false;  // the point projects outside the map: lit by definition
  bool empty_tile = false;   // its tile holds no geometry: lit
  float value = 0;           // shadow value used (depth units)
  LightSpacePoint light;     // the point in light space
};

struct CacheStats {
  uint64_t hits = 0;
  uint64_t misses = 0;         // fetches (blob read + decode)
  uint64_t shared_misses = 0;  // misses that waited for another thread's fetch of the same tile
  uint64_t locked_lookups = 0;  // lookups through the locked cache: pin misses, a batch's tiles, tile()
  uint64_t bytes = 0;
  uint64_t peak_bytes = 0;     // largest `bytes` so far
  uint64_t evictions = 0;
  uint64_t fetched_bytes = 0;  // blob bytes read from the source (stored, compressed)
  uint64_t tiles = 0;
};

class ShadowMap {
 public:
  struct Options {
    size_t cache_bytes = size_t(256) << 20;
  };
  // Opens `store_dir` read-only and validates its meta. Errors: not_found, corrupt_data, unsupported,
  // invalid_input when the build is incomplete (absent tiles would be ambiguous).
  static Result<std::unique_ptr<ShadowMap>> open(const std::filesystem::path& store_dir, Options options);
  static Result<std::unique_ptr<ShadowMap>> open(const std::filesystem::path& store_dir) {
    return open(store_dir, Options{});
  }
  // Opens the build `source` serves: reads and validates its meta and top trees now, tiles on demand.
  // Errors: those of the source, corrupt_data, unsupported, invalid_input for an incomplete build.
  static Result<std::unique_ptr<ShadowMap>> open(std::shared_ptr<const TileSource> source, Options options);

  const StoreMeta& meta() const { return meta_; }
  const LightFrame& frame() const { return frame_; }
  const TileLayout& layout() const { return layout_; }
  const TileSource& source() const { return *source_; }
  // The local store when the source is one (else nullptr), for serving or walking the stored blobs
  // unchanged: one process must not open the same LMDB directory twice.
  const store::Store* local_store() const { return local_ ? &local_->store() : nullptr; }
  // The first method of the build, used when a query names none.
  store::Method default_method() const { return meta_.methods.front(); }

  // Value at global texel (u, v) < resolution. Errors: unsupported method, corrupt tile, I/O.
  Result<float> texel_value(store::Method method, uint32_t u, uint32_t v, unsigned max_level = 255) const;
  // Decoded tile, nullptr for an empty tile. Errors as texel_value. Returns a reference the caller
  // owns (one reference-count update); the query paths read per-thread pins instead.
  Result<std::shared_ptr<const DecodedTile>> tile(store::Method method, TileCoord tile) const;
  // Loads `tiles` into the cache (ahead of queries, e.g. the tiles under a camera). Stops at the
  // first error. Tiles beyond the cache's budget evict earlier ones, as any lookup would.
  Status prefetch(store::Method method, std::span<const TileCoord> tiles) const;
  // Light-space tile of a world point, nullopt when it falls off the map.
  std::optional<TileCoord> tile_of(const Vec3& world) const;
  // Point query; `bias` in world units (default: the build's). `level`: level of detail counted from
  // the whole map's root (0) to the finest texels (log2 resolution, the default); coarser levels of
  // hierarchical methods stop the descent early (every level is a complete shadow map).
  Result<ShadowAnswer> query(const Vec3& world, store::Method method, std::optional<double> bias = {},
                             std::optional<unsigned> level = {}) const;
  // Percentage-closer filtering: the lit fraction of the k x k texels centred on the point's texel
  // (k odd, 1..kMaxPcfKernel), each compared with the point's depth. Kernels crossing tile borders
  // read the neighbour tiles; samples outside the map are lit. `answer.lit` is fraction > 0.5;
  // `answer.value` is the centre texel's value (descended only when `answer` is given).
  static constexpr unsigned kMaxPcfKernel = 63;
  Result<double> query_pcf(const Vec3& world, store::Method method, unsigned kernel, std::optional<double> bias = {},
                           std::optional<unsigned> level = {}, ShadowAnswer* answer = nullptr) const;
  // Batch queries, the way a game server or a simulation asks: out.lit[i] answers points[i] exactly
  // as query() (1 lit, 0 shadowed) or query_pcf() (the lit fraction) would; out.outside lists the
  // points off the map (lit), ascending. Points are sorted by tile and along the Morton curve inside
  // it, each tile is looked up once per run of its points, runs walk down a shared path (each point
  // resumes from the deepest node it shares with the previous one), and the work is split across
  // `threads`; raw point batches skip the sort (one read a point: each chunk of points is grouped
  // by tile in cache, client/shadow_batch.cpp). Errors: those of query() / query_pcf() (the first
  // one fails the whole batch, and leaves out.lit and out.outside empty).
  struct BatchOptions {
    unsigned kernel = 1;  // 1: point query; odd k: PCF k x k
    std::optional<double> bias;
    std::optional<unsigned> level;
    unsigned threads = 0;  // workers when no parallel_for is given; 0 = hardware threads
    // Runs fn(begin, end) over disjoint ranges covering [0, count) and returns when all are done
    // (e.g. a server's pool); empty: `threads` std::threads started for the call.
    std::function<void(size_t count, const std::function<void(size_t, size_t)>& fn)> parallel_for;
  };
  // One point in query_batch's sort (internal; here so BatchAnswers can keep the sort's buffers).
  struct BatchSortItem {
    uint64_t key;  // Morton code of the texel and maybe its u, v (client/batch_texel_keys.hpp), or all ones off the map
    uint32_t index;
    float threshold;  // biased depth
  };
  struct BatchAnswers {
    std::vector<float> lit;
    std::vector<uint32_t> outside;
    // The sort's buffers (32 bytes per point of the largest batch so far, plus its histograms, and
    // lit_bytes' 1 byte per point; raw point batches: 512 KiB per worker), kept for the next batch
    // answered into these answers: reusing one BatchAnswers for repeated batches skips
    // re-allocating them (zero-filled fresh pages: ~8,000 page faults per 1M-point batch).
    // Drop the answers (or assign `sort_items = {}` and clear the histogram) to free that memory.
    // The items in 2 MiB pages where the kernel allows: the sort's scatter writes to 4,096 buckets
    // at once, a page each with 4 KiB pages, which the TLB cannot hold (fzk_haus 16384², 1M points,
    // 1 thread, MH: +4-8 %).
    HugePageArray<BatchSortItem> sort_items;
    std::vector<uint32_t> sort_histogram;
    // Point answers as bytes (1 lit, 0 shadowed) before they become `lit`'s floats: the walk writes
    // them in the sort's order, so to random places, and bytes spread those writes over a quarter
    // of the cache lines floats would.
    std::vector<uint8_t> lit_bytes;
  };
  Status query_batch(std::span<const Vec3> points, store::Method method, const BatchOptions& options,
                     BatchAnswers& out) const;

  // Levels of the whole map: log2(resolution) + 1.
  unsigned level_count() const;

  CacheStats cache_stats() const;

 private:
  ShadowMap(std::shared_ptr<const TileSource> source, StoreMeta meta, LightFrame frame, TileLayout layout,
            Options options);
  static uint64_t next_id();

  Status check_method(store::Method method) const;
  // Refuses a bias below what `method`'s values answer for (StoreMeta::min_query_bias).
  Status check_bias(store::Method method, double bias_world) const;
  // The point in light space, flagged outside_map (lit, value +inf) when it falls off the map.
  ShadowAnswer project(const Vec3& world) const;
  // Validates a query and maps the point to light space; the answer is flagged outside_map (lit)
  // when it falls off the map. Also returns the max level inside a tile tree for `level`.
  Result<std::pair<ShadowAnswer, unsigned>> locate(const Vec3& world, double bias_world,
                                                   std::optional<unsigned> level) const;
  // True for a call every check passes (method present, bias allowed, finite point and bias): the
  // fast paths of query() and query_pcf() take it; the general paths give the errors.
  bool plain_query(const Vec3& world, store::Method method, double bias_world) const;
  // query_pcf() for the calls its fast path leaves: errors, coarse levels.
  Result<double> query_pcf_general(const Vec3& world, store::Method method, unsigned kernel, double bias_world,
                                   std::optional<unsigned> level, ShadowAnswer* answer_out) const;
  // The lit fraction of the kernel around `answer.light` (on the map), and *answer_out if asked.
  Result<double> pcf_fraction(store::Method method, unsigned kernel, double bias_world, unsigned max_level,
                              std::optional<unsigned> level, ShadowAnswer& answer, ShadowAnswer* answer_out) const;
  // query() for the calls its fast path leaves: errors, coarse levels.
  Result<ShadowAnswer> query_general(const Vec3& world, store::Method method, double bias_world,
                                     std::optional<unsigned> level) const;
  // Fills answer.value/lit/empty_tile from the tile under answer.light (on the map, method checked);
  // false with *error set when the tile cannot be read.
  bool sample_tile(store::Method method, double bias_world, unsigned max_level, ShadowAnswer& answer,
                   Error* error) const;
  // The receiver's depth, clamped to the far plane (1), minus the bias, as compared with stored
  // values by every method, point and PCF.
  float biased_depth(double depth, double bias_world) const;
  // Query level -> max level inside a tile tree (255 = finest).
  Result<unsigned> tile_max_level(std::optional<unsigned> level) const;

  // Value at global texel (u, v) for a level of detail at or above the tile level, from the
  // method's top tree; nullopt when the method has none (flat methods: the tile's value is used).
  std::optional<float> top_value(store::Method method, uint32_t u, uint32_t v, unsigned level) const;

  // The tile of a query (method already checked, coordinates inside the map): the calling thread's
  // pin when it holds one (no shared write), else pinned through the shared cache. Sets *tile
  // (nullptr: empty tile) and returns true, or sets *error and returns false.
  bool pinned_tile(store::Method method, uint32_t x, uint32_t y, const DecodedTile** tile, Error* error) const;
  bool pin_slow(store::Method method, uint32_t x, uint32_t y, const DecodedTile** tile, Error* error) const;
  // Through the shared cache: a cached tile, another thread's fetch in flight, or a fetch now.
  Result<std::shared_ptr<const DecodedTile>> shared_tile(const store::TileKey& key, uint64_t reported_hits) const;
  // Reads, checks and decodes one tile blob (no lock held).
  Result<std::shared_ptr<const DecodedTile>> fetch_tile(const store::TileKey& key, size_t* blob_bytes) const;

  // Per-query PCF over a kernel, the tiles it crosses included (method checked, point on the map).
  Result<uint64_t> pcf_lit_samples(store::Method method, int64_t cu, int64_t cv, unsigned kernel, float threshold,
                                   unsigned max_level, std::optional<unsigned> level) const;

  std::shared_ptr<const TileSource> source_;
  std::shared_ptr<const LmdbTileSource> local_;  // source_ when it is a local store
  std::map<store::Method, std::shared_ptr<const DecodedTile>> top_trees_;  // loaded at open
  StoreMeta meta_;
  LightFrame frame_;
  TileLayout layout_;
  Options options_;
  std::array<bool, 256> method_present_{};  // by method byte: one check per call, no search
  // By method byte: the least bias answered (StoreMeta::min_query_bias less a relative 1e-9 for the
  // rounding of two equal products), -infinity where any bias is.
  std::array<double, 256> bias_floor_{};
  unsigned tile_shift_ = 0;                 // log2(tile size)

  // Bumped (under cache_mutex_) whenever the cache evicts: threads then drop their pins. Read on
  // every lookup, written rarely: on a cache line of its own so the lock's writes do not share it.
  alignas(64) mutable std::atomic<uint64_t> epoch_{0};
  struct CacheEntry {
    std::shared_ptr<const DecodedTile> tile;  // nullptr: empty tile
    size_t bytes = 0;
    std::list<store::TileKey>::iterator lru;
  };
  struct InFlight {
    bool done = false;
    std::optional<Error> error;
  };
  alignas(64) mutable std::mutex cache_mutex_;
  mutable std::condition_variable fetched_;  // an in-flight fetch finished
  mutable std::map<store::TileKey, CacheEntry> cache_;
  mutable std::map<store::TileKey, std::shared_ptr<InFlight>> in_flight_;
  mutable std::list<store::TileKey> lru_;  // front = most recent
  mutable CacheStats stats_;
  const uint64_t id_;  // tells this map's entries in the per-thread pins from another's
};

}  // namespace shadowtiles
