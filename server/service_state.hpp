// ServiceState: what every route handler shares: the effective config, CORS policy, metrics, the
// batch pool and the open store. The store is attached once, after the server may already be
// listening: until then map() is null and the API answers 503 (DESIGN.md §10, /healthz).
// Thread safety: config/cors are immutable; metrics and pool are thread-safe; attach() publishes
// the map with release ordering and map() reads it with acquire, so a handler that sees the map
// sees it fully constructed. attach() succeeds once; call it from one thread.
#pragma once

#include <atomic>
#include <memory>

#include "client/shadow_map.hpp"
#include "server/batch_pool.hpp"
#include "server/cors.hpp"
#include "server/metrics.hpp"
#include "server/server_config.hpp"

namespace shadowtiles::server {

struct ServiceState {
  explicit ServiceState(ServerConfig c) : config(std::move(c)), cors(config.cors_origins), pool(config.threads) {}

  const ShadowMap* map() const { return map_.load(std::memory_order_acquire); }
  // False (and `map` dropped) when a map is already attached: replacing it under running handlers
  // would free what they read.
  bool attach(std::unique_ptr<ShadowMap> map) {
    if (owned_) return false;
    owned_ = std::move(map);
    map_.store(owned_.get(), std::memory_order_release);
    return true;
  }

  const ServerConfig config;
  const CorsPolicy cors;
  Metrics metrics;
  BatchPool pool;

 private:
  std::unique_ptr<ShadowMap> owned_;
  std::atomic<const ShadowMap*> map_{nullptr};
};

}  // namespace shadowtiles::server
