#include "bench/harness/http_cold_start.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "client/shadow_map.hpp"
#include "common/byte_order.hpp"

#ifdef SHADOWTILES_HAVE_SERVER
#include <httplib.h>

#include "client/http_tile_source.hpp"
#include "server/server.hpp"
#endif

namespace shadowtiles::bench {

#ifndef SHADOWTILES_HAVE_SERVER
bool http_cold_start_available() { return false; }
Result<HttpColdStart> measure_http_cold_start(const std::filesystem::path&, store::Method, std::span<const Vec3>,
                                              unsigned, uint64_t) {
  return make_error(ErrorCode::unsupported, "this build has no HTTP server");
}
#else
namespace {

using Clock = std::chrono::steady_clock;

// The binary batch body: little-endian float32 x, y, z per point (config/README.md).
std::string binary_body(std::span<const Vec3> points) {
  std::string body(points.size() * 12, '\0');
  for (size_t i = 0; i < points.size(); ++i)
    for (size_t axis = 0; axis < 3; ++axis)
      bytes::store_le(reinterpret_cast<uint8_t*>(body.data()) + i * 12 + axis * 4,
               std::bit_cast<uint32_t>(float(points[i][axis])));
  return body;
}

// A counter of the server's /metrics text (0 when absent).
uint64_t metric_value(const std::string& text, const std::string& name) {
  const size_t at = text.find("\n" + name + " ");
  if (at == std::string::npos) return 0;
  return std::stoull(text.substr(at + name.size() + 2));
}

// The server of one measurement, serving on its own thread until destroyed.
struct RunningServer {
  std::unique_ptr<server::Server> server;
  std::thread thread;
  std::atomic<bool> finished{false};
  void start() {
    thread = std::thread([this] {
      (void)server->run();
      finished = true;
    });
  }
  ~RunningServer() {
    if (!thread.joinable()) return;
    // A stop() racing with the very start of run() can be missed (server.hpp): repeat it.
    for (server->stop(); !finished; server->stop()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    thread.join();
  }
};

}  // namespace

bool http_cold_start_available() { return true; }

Result<HttpColdStart> measure_http_cold_start(const std::filesystem::path& store_dir, store::Method method,
                                              std::span<const Vec3> points, unsigned threads, uint64_t cache_bytes) {
  server::ServerConfig config;
  config.port = 0;
  config.threads = std::max(1u, threads);
  config.cache_bytes = cache_bytes;
  config.max_batch_points = std::max<uint64_t>(config.max_batch_points, points.size());
  config.max_body_bytes = std::max<uint64_t>(config.max_body_bytes, points.size() * 12 + 1024);
  config.max_batch_cost = std::max<uint64_t>(config.max_batch_cost, points.size());
  config.body_timeout_s = config.write_timeout_s = 60;
  config.reload_poll_s = 0;
  auto bound = server::Server::bind(config);
  if (!bound) return bound.error();
  RunningServer running;
  running.server = std::move(*bound);
  if (Status s = running.server->attach_store(store_dir); !s) return s.error();
  running.start();
  const int port = running.server->port();

  HttpColdStart out;
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(std::chrono::seconds(120));
  client.set_write_timeout(std::chrono::seconds(120));
  const std::string body = binary_body(points);
  const std::string path = std::string("/v1/shadow?method=") + store::method_name(method);
  httplib::Headers no_expect{{"Expect", ""}};  // time the server, not a 100-continue round trip
  const auto start = Clock::now();
  auto res = client.Post(path, no_expect, body, "application/octet-stream");
  out.post_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (!res) return make_error(ErrorCode::io_error, "cold batch POST: " + httplib::to_string(res.error()));
  if (res->status != 200 || res->body.size() != points.size() * 4)
    return make_error(ErrorCode::io_error, "cold batch POST answered " + std::to_string(res->status) + " with " +
                                               std::to_string(res->body.size()) + " bytes");
  auto metrics = client.Get("/metrics");
  if (!metrics || metrics->status != 200) return make_error(ErrorCode::io_error, "cannot read /metrics");
  out.post_bytes_read = metric_value(metrics->body, "shadowtiles_tile_cache_fetched_bytes_total");

  // Warm: the 100k-point binary batch, repeated on this keep-alive connection.
  {
    const size_t count = std::min(points.size(), kWarmHttpBatchPoints);
    const std::string warm_body = binary_body(points.first(count));
    std::vector<double> rates;
    for (int round = 0; round < 12; ++round) {
      const auto t0 = Clock::now();
      auto warm = client.Post(path, no_expect, warm_body, "application/octet-stream");
      const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      if (!warm) return make_error(ErrorCode::io_error, "warm batch POST: " + httplib::to_string(warm.error()));
      if (warm->status != 200 || warm->body.size() != count * 4)
        return make_error(ErrorCode::io_error, "warm batch POST answered " + std::to_string(warm->status) + " with " +
                                                   std::to_string(warm->body.size()) + " bytes");
      if (round >= 2) rates.push_back(double(count) / seconds);
    }
    std::sort(rates.begin(), rates.end());
    out.warm_batch_points = count;
    out.warm_post_lps_median = (rates[rates.size() / 2 - 1] + rates[rates.size() / 2]) / 2;
    out.warm_post_lps_best = rates.back();
  }

  // A streaming client on the same server: its own empty cache, tiles fetched over HTTP.
  const auto stream_start = Clock::now();
  auto source = HttpTileSource::open("http://127.0.0.1:" + std::to_string(port), HttpTileSource::Options{});
  if (!source) return source.error();
  ShadowMap::Options options;
  options.cache_bytes = cache_bytes;
  auto map = ShadowMap::open(std::shared_ptr<const TileSource>(*source), options);
  if (!map) return map.error();
  ShadowMap::BatchOptions batch;
  batch.threads = threads;
  ShadowMap::BatchAnswers answers;
  if (Status s = (*map)->query_batch(points, method, batch, answers); !s) return s.error();
  out.stream_seconds = std::chrono::duration<double>(Clock::now() - stream_start).count();
  out.stream_bytes_fetched = (*map)->cache_stats().fetched_bytes;
  return out;
}
#endif

}  // namespace shadowtiles::bench
