// HttpTileSource: a TileSource streaming a build from `shadowtiles serve` (docs/architecture.md §10), so a
// ShadowMap answers queries locally from tiles fetched on demand.
//
// Routes used: GET /v1/build (the meta record as stored; ETag = build id), then preferably the
// immutable /v1/builds/{build id}/skiplist?method= (a method's top-tree blob, 404 = none) and
// /v1/builds/{build id}/tiles/{method}/{level}/{x}/{y} (204 = empty tile), probed at open; a server
// without them is read through /v1/skiplist and /v1/tiles/... instead. Connections are HTTP/1.1 keep-alive, one per concurrent caller (a small pool grows to
// the number of threads fetching at once), so 2 decoding threads fetch concurrently.
//
// Checks: every blob is verified here (store::check_blob: header, sizes, checksum; method matches
// the key) before it is returned or cached. A blob failing them is fetched once more (a bit flipped
// on the way), then reported as corrupt_data, never returned. A server answering 500 corrupt_data
// (its stored blob fails its checks) is reported as corrupt_data at once.
// Network errors (connect, read, timeouts) and 502/503/504 are retried with exponential backoff
// (Options::max_attempts in all), then reported as io_error naming the URL and the cause.
// With build routes, a 404 on a tile means the server now serves another build: not_found, saying so.
//
// Disk cache (optional, Options::disk_cache_dir): blobs keyed by (build id, tile), bounded in bytes.
// A cached blob is revalidated with If-None-Match (its checksum is its ETag; 304 = still current)
// unless Options::revalidate is false (safe with build routes: those URLs never change content).
// When the server is unreachable, revalidation falls back to the cached blob (it is verified and
// belongs to the same build id).
//
// Errors: open → invalid_input for a malformed URL, io_error when the server cannot be reached,
// not_found/corrupt_data/unsupported for what /v1/build returns. Members as described above.
// Thread safety: all members may be called concurrently.
// Untrusted input: everything the server sends is validated (status, sizes, blob checks; the
// build id is sanitised before it names a directory); a hostile server can cause errors, not a crash.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "client/disk_tile_cache.hpp"
#include "client/tile_source.hpp"

namespace httplib {
class Client;
}

namespace shadowtiles {

struct HttpFetchStats {
  uint64_t requests = 0;        // HTTP requests sent (every attempt counts)
  uint64_t retries = 0;         // attempts after a network error or 502/503/504
  uint64_t tiles_fetched = 0;   // tile answers received: 200 (blob) or 204 (empty)
  uint64_t bytes_received = 0;  // body bytes of 200 answers
  uint64_t not_modified = 0;    // 304 answers (disk cache revalidated)
  uint64_t disk_hits = 0;       // answers taken from the disk cache
  uint64_t corrupt_refetches = 0;  // blobs that failed their checks and were fetched again
};

class HttpTileSource final : public TileSource {
 public:
  struct Options {
    unsigned max_attempts = 4;  // per request, including the first
    std::chrono::milliseconds initial_backoff{100};  // doubled after each failed attempt...
    std::chrono::milliseconds max_backoff{2000};     // ...up to this
    std::chrono::milliseconds connect_timeout{3000};
    std::chrono::milliseconds read_timeout{30000};
    bool use_build_routes = true;  // prefer /v1/builds/{id}/tiles/... when the server has them
    std::filesystem::path disk_cache_dir;  // empty: no disk cache
    uint64_t disk_cache_bytes = uint64_t(1) << 30;
    bool revalidate = true;  // ask the server (If-None-Match) before using a disk-cached blob
  };

  // `url`: http://host[:port][/prefix] (https:// too). Fetches /v1/build now.
  static Result<std::shared_ptr<HttpTileSource>> open(const std::string& url, const Options& options);
  ~HttpTileSource() override;

  Result<std::string> meta_text() const override;  // fetched at open: the build this source serves
  Result<std::optional<std::vector<uint8_t>>> tile_blob(const store::TileKey& key) const override;
  Result<std::optional<std::vector<uint8_t>>> top_blob(store::Method method) const override;
  std::string describe() const override;

  const std::string& build_id() const { return build_id_; }
  bool uses_build_routes() const { return build_routes_; }
  HttpFetchStats stats() const;

 private:
  HttpTileSource(std::string base_url, std::string path_prefix, Options options);

  struct Response {
    int status = 0;
    std::string body;
    std::string etag;
    std::string content_type;
  };
  // GET with retries and backoff; an error only when every attempt failed on the network (or got
  // 502/503/504). `if_none_match` adds that header when not empty.
  Result<Response> get(const std::string& path, const std::string& if_none_match = {}) const;
  // A blob route: 200 → checked blob (refetched once when it fails), 204/404 per `absent_statuses`
  // → nullopt, with the disk cache in front under `cache_name`.
  Result<std::optional<std::vector<uint8_t>>> fetch_blob(const std::string& path, store::Method method,
                                                         const std::string& cache_name, bool is_tile) const;
  std::string tile_path(const store::TileKey& key) const;

  std::unique_ptr<httplib::Client> acquire_client() const;
  void release_client(std::unique_ptr<httplib::Client> client) const;

  std::string base_url_;     // scheme://host:port
  std::string path_prefix_;  // "" or "/prefix" (no trailing slash)
  Options options_;
  std::string meta_text_;
  std::string build_id_;
  bool build_routes_ = false;
  std::unique_ptr<DiskTileCache> disk_cache_;

  mutable std::mutex pool_mutex_;
  mutable std::vector<std::unique_ptr<httplib::Client>> idle_clients_;

  mutable std::atomic<uint64_t> requests_{0}, retries_{0}, tiles_fetched_{0}, bytes_received_{0}, not_modified_{0},
      disk_hits_{0}, corrupt_refetches_{0};
};

}  // namespace shadowtiles
