// ServiceState: what every route handler shares: the effective config, CORS policy, metrics, the
// batch pool and the build being served. The build is published after the server may already be
// listening: until then map() is null and the API answers 503 (DESIGN.md §10, /healthz). A reload
// publishes a new build (DESIGN.md §9 "swapping to a new build"): a handler takes map() once and
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
#include "server/metrics.hpp"
#include "server/render_pool.hpp"
#include "server/tile_summary_cache.hpp"
#include "server/server_config.hpp"

namespace shadowtiles::server {

struct ServiceState {
  explicit ServiceState(ServerConfig c)
      : config(std::move(c)),
        cors(config.cors_origins),
        pool(config.threads),
        render_cache(size_t(config.render_cache_bytes)),
        render_pool(config.render_threads, config.render_queue) {}

  std::shared_ptr<const ShadowMap> map() const { return map_.load(std::memory_order_acquire); }
  void publish(std::shared_ptr<const ShadowMap> map) { map_.store(std::move(map), std::memory_order_release); }

  const ServerConfig config;
  const CorsPolicy cors;
  Metrics metrics;
  BatchPool pool;
  TileSummaryCache render_cache;   // previews and tile sizes for /v1/render
  RenderPool render_pool;          // /v1/render only, never the query workers (destroyed first)

 private:
  std::atomic<std::shared_ptr<const ShadowMap>> map_;
};

}  // namespace shadowtiles::server
