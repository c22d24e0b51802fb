// ServiceState: what every route handler shares: the effective config, CORS policy, metrics, the
// batch pool, the query slots and the build being served. The build is published after the server may already be
// listening: until then map() is null and the API answers 503 (docs/architecture.md §10, /healthz). A reload
// publishes a new build (docs/architecture.md §9 "swapping to a new build"): a handler takes map() once and
// keeps that shared_ptr for the whole request, so requests in flight finish on the build they
// started with, which is closed when the last of them drops it.
// Thread safety: config/cors are immutable; metrics and pool are thread-safe; map()/publish() are
// atomic (acquire/release), so a handler that sees a map sees it fully constructed.
#pragma once

#include <atomic>
#include <memory>

#include "client/shadow_map.hpp"
#include "server/batch_pool.hpp"
#include "server/cors.hpp"
#include "server/http_response.hpp"
#include "server/metrics.hpp"
#include "server/query_slots.hpp"
#include "server/render_pool.hpp"
#include "server/tile_summary_cache.hpp"
#include "server/server_config.hpp"
#include "server/verified_blobs.hpp"

namespace shadowtiles::server {

struct ServiceState {
  explicit ServiceState(ServerConfig c)
      : config(std::move(c)),
        cors(config.cors_origins),
        pool(config.threads),
        slots(config.threads),
        render_cache(size_t(config.render_cache_bytes)),
        render_pool(config.render_threads, config.render_queue),
        verified_blobs(std::chrono::milliseconds(config.blob_recheck_ms), kVerifiedBlobEntries) {}

  // ~100 bytes each: enough for every tile a server streams hot, small beside the tile cache.
  static constexpr size_t kVerifiedBlobEntries = 65536;

  std::shared_ptr<const ShadowMap> map() const { return map_.load(std::memory_order_acquire); }
  void publish(std::shared_ptr<const ShadowMap> map) { map_.store(std::move(map), std::memory_order_release); }

  const ServerConfig config;
  const CorsPolicy cors;
  Metrics metrics;
  BatchPool pool;
  QuerySlots slots;                // `threads` query workers; see take_query_slot
  TileSummaryCache render_cache;   // previews and tile sizes for /v1/render
  RenderPool render_pool;          // /v1/render only, never the query workers (destroyed first)
  VerifiedBlobs verified_blobs;    // blobs whose checks passed lately (tile and skip-list GETs)

 private:
  std::atomic<std::shared_ptr<const ShadowMap>> map_;
};

// One of the query slots for the rest of a handler's work, taken after the request was read; an
// empty slot (and 503 `busy` sent) when none frees up within query_wait_ms.
inline QuerySlots::Slot take_query_slot(ServiceState& state, httplib::Response& res) {
  auto slot = state.slots.acquire(std::chrono::milliseconds(state.config.query_wait_ms));
  if (!slot) {
    state.metrics.add_rejection(Metrics::Rejection::query_slot_wait);
    res.set_header("Retry-After", "1");
    send_error(res, 503, "busy", "every query worker is busy; retry later");
  }
  return slot;
}

}  // namespace shadowtiles::server
