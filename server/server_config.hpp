// ServerConfig: everything `shadowtiles serve` can be told (docs/architecture.md §10), read from a JSON file
// (config/serve.json, documented in config/README.md) and overridden by CLI flags.
//
// Parsing is strict so a typo never silently falls back to a default: an unknown key, a value of the
// wrong type or out of its range is an invalid_input error naming the key. Keys absent from the file
// keep their defaults (below). validate() re-checks a config after CLI overrides.
// Errors: invalid_input (bad JSON, unknown key, bad value); not_found / io_error (config file).
// Thread safety: plain value type. Safe on untrusted input (the file is parsed without exceptions
// escaping and every number is range-checked).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/result.hpp"

namespace shadowtiles::server {

struct ServerConfig {
  std::string store;               // store directory to serve; the positional STORE argument overrides it
  std::string host = "127.0.0.1";  // loopback unless told otherwise
  int port = 8080;                 // 0: an ephemeral port (Server::port() tells which)
  unsigned threads = 2;            // HTTP workers, also the batch split width
  uint64_t cache_bytes = uint64_t(256) << 20;  // decoded tile cache budget
  uint64_t max_body_bytes = uint64_t(16) << 20;  // larger request bodies → 413
  uint64_t max_batch_points = 1'000'000;         // more points in one batch → 413
  unsigned max_pcf = 15;                         // largest PCF kernel side accepted (odd)
  uint64_t cache_control_max_age = 86400;        // seconds, for stored blobs
  std::vector<std::string> cors_origins;         // exact origins allowed; empty = CORS off
  unsigned read_timeout_s = 5;           // request line + headers, from the request's first byte
  unsigned body_timeout_s = 10;          // the whole request body, from the end of the headers
  unsigned write_timeout_s = 5;          // the whole response, from its first byte
  unsigned max_connections = 64;         // connections served at once (one I/O thread each); beyond: 503
  unsigned max_connections_per_address = 0;  // 0: no per-address cap; else beyond it: 503
  unsigned max_pinned_sends = 48;        // blob sends from the store's map at once (LMDB reader each); beyond: copy
  unsigned blob_recheck_ms = 1000;       // a served blob's passed check stands this long; 0: check every GET
  uint64_t max_batch_cost = 16'000'000;  // points x kernel^2 of one batch; beyond: 413
  unsigned query_wait_ms = 2000;         // longest wait for a query slot; beyond: 503 busy
  unsigned keep_alive_max_count = 1000;  // requests per keep-alive connection (nginx's default)
  unsigned keep_alive_timeout_s = 5;     // idle keep-alive connection closed after this
  unsigned reload_poll_s = 5;            // check the store path for a new build this often; 0: only on SIGHUP
  unsigned render_threads = 1;           // the inspector's /v1/render pool, apart from the HTTP workers
  unsigned render_queue = 32;            // renders waiting beyond this → 503
  unsigned render_timeout_ms = 5000;     // one render's time budget → 503 when exceeded
  uint64_t render_cache_bytes = uint64_t(48) << 20;  // decoded previews kept for rendering
  std::string leaflet_dir = "/usr/share/javascript/leaflet";  // Debian's libjs-leaflet, served to the page
  std::string replica_name;              // X-Shadow-Replica on every answer; empty: "<hostname>:<port>"

  // Range checks shared by the file parser and CLI overrides.
  Status validate() const;
  nlohmann::json to_json() const;
  // Keys of `json` override `base`; unknown keys and bad values fail.
  static Result<ServerConfig> from_json(const nlohmann::json& json, ServerConfig base);
  static Result<ServerConfig> from_json(const nlohmann::json& json);
  static Result<ServerConfig> load(const std::filesystem::path& file);
};

}  // namespace shadowtiles::server
