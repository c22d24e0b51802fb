// Cold start over HTTP (issue 15): the first batch of the bench's surface points answered through
// a freshly started `shadowtiles serve` on loopback, two ways a user meets it:
//   - POST /v1/shadow (binary float32 body) to a server that has just opened the store: seconds from
//     the request to the whole answer, and the stored blob bytes the server read for it (its
//     shadowtiles_tile_cache_fetched_bytes_total metric);
//   - a streaming client (ShadowMap over HttpTileSource) opened on that server, answering the same
//     points with query_batch: seconds, and the blob bytes it fetched over HTTP;
// and, once that server is warm, issue 15's HTTP batch figure: binary POSTs of the first 100k points
// on one keep-alive connection (2 warm-up, then the median and best of 10), points/s end to end.
// The local cold start (ShadowMap on the store directory) is bench_runner's own.
// Errors: the server cannot bind or open the store, a request fails or answers the wrong count.
// Thread safety: one call at a time (it runs a server for its duration).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "codec/light_frame.hpp"
#include "common/result.hpp"
#include "store/method.hpp"

namespace shadowtiles::bench {

struct HttpColdStart {
  double post_seconds = 0;          // POST of every point to a fresh server, until the answer is read
  uint64_t post_bytes_read = 0;     // blob bytes that server read from its store
  double stream_seconds = 0;        // open over HTTP + query_batch on a fresh streaming client
  uint64_t stream_bytes_fetched = 0;  // blob bytes that client fetched over HTTP
  uint64_t warm_batch_points = 0;     // points per warm POST (100k, or all if fewer)
  double warm_post_lps_median = 0;    // points/s of a warm POST, request to whole answer
  double warm_post_lps_best = 0;
};

inline constexpr size_t kWarmHttpBatchPoints = 100000;

// False (no error) when this build has no HTTP server (cpp-httplib missing at configure time).
bool http_cold_start_available();

Result<HttpColdStart> measure_http_cold_start(const std::filesystem::path& store_dir, store::Method method,
                                              std::span<const Vec3> points, unsigned threads, uint64_t cache_bytes);

}  // namespace shadowtiles::bench
