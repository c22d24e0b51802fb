#include "server/metrics.hpp"

#include <algorithm>
#include <cstdio>

namespace shadowtiles::server {

Metrics::Route Metrics::route_of(std::string_view path) {
  if (path == "/v1/meta") return Route::meta;
  if (path == "/v1/shadow") return Route::shadow;
  if (path.starts_with("/v1/tiles/")) return Route::tiles;
  if (path == "/v1/skiplist") return Route::skiplist;
  if (path == "/healthz") return Route::healthz;
  if (path == "/metrics") return Route::metrics;
  return Route::other;
}

const char* Metrics::route_name(Route route) {
  switch (route) {
    case Route::meta: return "/v1/meta";
    case Route::shadow: return "/v1/shadow";
    case Route::tiles: return "/v1/tiles";
    case Route::skiplist: return "/v1/skiplist";
    case Route::healthz: return "/healthz";
    case Route::metrics: return "/metrics";
    case Route::other: break;
  }
  return "other";
}

void Metrics::observe(Route route, std::string_view http_method, int status, std::optional<double> seconds) {
  static constexpr std::string_view kMethods[] = {"GET", "HEAD", "POST", "OPTIONS"};
  std::string method = std::find(std::begin(kMethods), std::end(kMethods), http_method) != std::end(kMethods)
                           ? std::string(http_method)
                           : "other";
  if (status < 100 || status > 599) status = 0;
  std::lock_guard lock(mutex_);
  ++requests_[{route, std::move(method), status}];
  if (seconds) {
    Histogram& h = latency_[size_t(route)];
    size_t bucket = std::lower_bound(kLatencyBuckets.begin(), kLatencyBuckets.end(), *seconds) - kLatencyBuckets.begin();
    ++h.buckets[bucket];
    h.sum += *seconds;
    ++h.count;
  }
}

const char* Metrics::rejection_name(Rejection reason) {
  switch (reason) {
    case Rejection::over_max_connections: return "over_max_connections";
    case Rejection::over_address_cap: return "over_address_cap";
    case Rejection::header_deadline: return "header_deadline";
    case Rejection::body_deadline: return "body_deadline";
    case Rejection::response_deadline: return "response_deadline";
    case Rejection::body_too_large: return "body_too_large";
    case Rejection::batch_too_costly: return "batch_too_costly";
    case Rejection::query_slot_wait: return "query_slot_wait";
  }
  return "other";
}

std::string Metrics::render(const std::optional<CacheStats>& cache) const {
  std::string out;
  char line[1024];
  auto emit = [&](const char* format, auto... args) {
    std::snprintf(line, sizeof line, format, args...);
    out += line;
  };
  // One unlabelled sample with its HELP and TYPE lines.
  auto single = [&](const char* name, const char* type, const char* help, uint64_t value) {
    emit("# HELP %s %s\n# TYPE %s %s\n%s %llu\n", name, help, name, type, name, (unsigned long long)value);
  };
  std::lock_guard lock(mutex_);
  out += "# HELP shadowtiles_http_requests_total HTTP requests answered, by route, method and status.\n"
         "# TYPE shadowtiles_http_requests_total counter\n";
  for (const auto& [key, count] : requests_) {
    const auto& [route, method, status] = key;
    emit("shadowtiles_http_requests_total{route=\"%s\",method=\"%s\",status=\"%d\"} %llu\n", route_name(route),
         method.c_str(), status, (unsigned long long)count);
  }
  out += "# HELP shadowtiles_http_request_duration_seconds Time from the request headers to the response.\n"
         "# TYPE shadowtiles_http_request_duration_seconds histogram\n";
  for (size_t r = 0; r < kRouteCount; ++r) {
    const Histogram& h = latency_[r];
    if (h.count == 0) continue;
    const char* route = route_name(Route(r));
    uint64_t cumulative = 0;
    for (size_t b = 0; b < kLatencyBuckets.size(); ++b) {
      cumulative += h.buckets[b];
      emit("shadowtiles_http_request_duration_seconds_bucket{route=\"%s\",le=\"%g\"} %llu\n", route,
           kLatencyBuckets[b], (unsigned long long)cumulative);
    }
    emit("shadowtiles_http_request_duration_seconds_bucket{route=\"%s\",le=\"+Inf\"} %llu\n", route,
         (unsigned long long)h.count);
    emit("shadowtiles_http_request_duration_seconds_sum{route=\"%s\"} %.9g\n", route, h.sum);
    emit("shadowtiles_http_request_duration_seconds_count{route=\"%s\"} %llu\n", route, (unsigned long long)h.count);
  }
  single("shadowtiles_points_answered_total", "counter", "Points answered by /v1/shadow (single and batch).",
         points_.load(std::memory_order_relaxed));
  single("shadowtiles_corrupt_blobs_total", "counter", "Stored blobs that failed their checks and were not served.",
         corrupt_blobs_.load(std::memory_order_relaxed));
  out += "# HELP shadowtiles_rejections_total Connections and requests refused to protect the server, by reason.\n"
         "# TYPE shadowtiles_rejections_total counter\n";
  for (size_t r = 0; r < kRejectionCount; ++r)
    emit("shadowtiles_rejections_total{reason=\"%s\"} %llu\n", rejection_name(Rejection(r)),
         (unsigned long long)rejections_[r].load(std::memory_order_relaxed));
  if (cache) {
    single("shadowtiles_tile_cache_hits_total", "counter", "Decoded tile cache hits.", cache->hits);
    single("shadowtiles_tile_cache_misses_total", "counter", "Decoded tile cache misses (tile read and decoded).",
           cache->misses);
    single("shadowtiles_tile_cache_locked_lookups_total", "counter",
           "Tile lookups made through the cache's lock (a query thread's pin misses, a batch's tiles); "
           "about one per query means the per-thread pins thrash.",
           cache->locked_lookups);
    single("shadowtiles_tile_cache_fetched_bytes_total", "counter",
           "Stored blob bytes read into the tile cache (compressed, as stored).", cache->fetched_bytes);
    single("shadowtiles_tile_cache_bytes", "gauge", "Bytes held by decoded tiles in the cache.", cache->bytes);
    single("shadowtiles_tile_cache_tiles", "gauge", "Tiles in the cache (empty tiles included).", cache->tiles);
  }
  return out;
}

}  // namespace shadowtiles::server
