// Server: the shadowtiles HTTP service (docs/architecture.md §10, API in config/README.md) on cpp-httplib.
//
// Lifecycle: bind() validates the config and binds the listening socket (port 0 → an ephemeral
// port, see port()); attach_store() opens the store read-only through ShadowMap (tile cache sized by
// cache_bytes) and from then on /healthz is 200 and the API answers (before: 503); run() serves on
// `threads` workers until stop(), then finishes every accepted connection (in-flight requests
// drain) and returns. The store can be attached while run() is already serving.
//
// Swapping builds (docs/architecture.md §9): the server holds a shared serving lock on the directory it serves
// (store/serving_lock.hpp), so `shadowtiles build` refuses to rewrite it; a new build goes into a
// new directory. reload() — called on SIGHUP and every `reload_poll_s` seconds — resolves the store
// path again (a symlink repointed with `ln -sfn`), opens and validates the new build, then publishes
// it atomically: requests in flight finish on the old build, which closes when the last one ends.
// A path that does not hold a complete build yet (missing, incomplete, being written) keeps the
// current build served, or 503 until the first one opens.
//
// Errors: bind → invalid_input (bad config), io_error (address cannot be bound); attach_store →
// ShadowMap::open's errors; run → io_error if the listener fails.
// Thread safety: stop() and port() may be called from any thread at any time (not from a signal
// handler: use a thread that waits for signals, see shutdown_signals.hpp). attach_store() once, from
// one thread. Handlers run concurrently on the worker threads and share only thread-safe state.
// Untrusted input: every request is parsed strictly; a client can cause 4xx answers but never a
// crash, a hang beyond the configured timeouts or a 5xx (only a store failing its checks gives 5xx).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "server/server_config.hpp"
#include "common/result.hpp"

namespace shadowtiles {
class ShadowMap;
}

namespace shadowtiles::server {

class Server {
 public:
  static Result<std::unique_ptr<Server>> bind(const ServerConfig& config);
  // Precondition: run() is not running (call stop() and wait for it to return first).
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  int port() const;
  const ServerConfig& config() const;

  // Errors: ShadowMap::open's; invalid_input when a store is already attached or being written.
  // With reload_poll_s > 0 the path keeps being polled even when this first open fails.
  Status attach_store(const std::filesystem::path& store_dir);
  // Serves an already open map (tests); no reloads.
  Status attach(std::unique_ptr<ShadowMap> map);
  // Checks the store path for a new build and swaps to it; true when it swapped. Errors leave the
  // current build served (e.g. the new one is incomplete).
  Result<bool> reload();
  // The served build's id (meta config_hash), empty before one is open.
  std::string build_id() const;

  // Serves one already-connected socket on the calling thread, with every route, limit and deadline
  // of run() but outside the connection caps; returns when the client is done. The caller closes
  // `fd`. For fuzz/fuzz_http.cpp (hostile bytes through a socketpair, no listener thread).
  void serve_connection(int fd);

  // Blocks until stop(); returns at once if stop() was already called.
  Status run();
  // Stops accepting; run() returns once accepted connections are done. Idempotent. A stop() racing
  // with the very start of run() can be missed by httplib: callers that stop on a signal should
  // repeat stop() until run() returns (ShutdownSignals does).
  void stop();

 private:
  struct Impl;
  explicit Server(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadowtiles::server
