// Metrics: the counters behind GET /metrics, rendered in the Prometheus text exposition format
// (version 0.0.4): requests by route, HTTP method and status; a request latency histogram by route;
// points answered; corrupt blobs refused; and the decoded-tile cache (hits, misses, bytes, tiles)
// from ShadowMap::cache_stats(); requests and connections refused, by reason.
// Label values come from fixed sets (route_of() folds every unknown path into "other"), so a client
// cannot grow the metric set by sending random URLs.
// Thread safety: every member may be called concurrently.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>

#include "client/shadow_map.hpp"

namespace shadowtiles::server {

class Metrics {
 public:
  enum class Route { meta, shadow, tiles, skiplist, healthz, metrics, other };
  static constexpr size_t kRouteCount = 7;
  // Upper bounds (seconds) of the latency buckets; +Inf is implicit.
  static constexpr std::array<double, 12> kLatencyBuckets = {0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005,
                                                             0.01,   0.025,   0.05,   0.1,   0.5,    2.5};

  // Requests and connections refused to protect the server (shadowtiles_rejections_total{reason}).
  enum class Rejection {
    over_max_connections,
    over_address_cap,
    header_deadline,
    body_deadline,
    response_deadline,
    body_too_large,
    batch_too_costly,
    query_slot_wait
  };
  static constexpr size_t kRejectionCount = 8;
  static const char* rejection_name(Rejection reason);

  static Route route_of(std::string_view path);
  static const char* route_name(Route route);

  // One finished request; `seconds` absent when its start was not seen (rejected before routing).
  void observe(Route route, std::string_view http_method, int status, std::optional<double> seconds);
  void add_points(uint64_t count) { points_.fetch_add(count, std::memory_order_relaxed); }
  void add_corrupt_blob() { corrupt_blobs_.fetch_add(1, std::memory_order_relaxed); }
  void add_rejection(Rejection reason) { rejections_[size_t(reason)].fetch_add(1, std::memory_order_relaxed); }
  uint64_t rejections(Rejection reason) const { return rejections_[size_t(reason)].load(std::memory_order_relaxed); }

  // `cache`: absent before the store is attached.
  std::string render(const std::optional<CacheStats>& cache) const;

 private:
  struct Histogram {
    std::array<uint64_t, kLatencyBuckets.size() + 1> buckets{};  // non-cumulative; last = +Inf
    double sum = 0;
    uint64_t count = 0;
  };
  mutable std::mutex mutex_;
  std::map<std::tuple<Route, std::string, int>, uint64_t> requests_;
  std::array<Histogram, kRouteCount> latency_{};
  std::atomic<uint64_t> points_{0};
  std::atomic<uint64_t> corrupt_blobs_{0};
  std::array<std::atomic<uint64_t>, kRejectionCount> rejections_{};
};

}  // namespace shadowtiles::server
