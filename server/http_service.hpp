// HttpService: cpp-httplib's Server with our own per-connection loop (it overrides the virtual
// process_and_close_socket, as httplib's SSLServer does). httplib still parses requests, routes and
// writes responses; this class owns what happens around them:
//   - every connection runs on an I/O thread (ConnectionQueue: up to max_connections of them), never
//     on a query slot, so idle keep-alive and slow clients cannot hold the threads that answer;
//   - ConnectionStream enforces the per-request header, body and response deadlines;
//   - a connection over max_connections, or over max_connections_per_address for its address,
//     gets a fast 503 and is closed (shed_connection);
//   - a request whose headers or body ran out of time gets 408 and the connection is closed, and so
//     is any connection whose request body was left unread (an early 413).
// current() gives the pre-routing hook the connection of the request it sees.
// Thread safety: as httplib::Server; process_and_close_socket runs concurrently on I/O threads.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include <httplib.h>

#include "server/connection_stream.hpp"

namespace shadowtiles::server {

class Metrics;

struct ConnectionPolicy {
  ConnectionStream::Limits limits;
  std::chrono::milliseconds keep_alive_timeout{5000};
  unsigned keep_alive_max_count = 100;
  unsigned max_connections_per_address = 0;  // 0: no per-address cap
};

class HttpService : public httplib::Server {
 public:
  HttpService(ConnectionPolicy policy, Metrics& metrics) : policy_(policy), metrics_(metrics) {}

  // After bind: httplib listens with a backlog of 5, so a burst of new connections (64 clients
  // connecting at once) has SYNs dropped and waits for the 1 s retransmit. Raises it to SOMAXCONN.
  void widen_listen_backlog();

  // The connection serving the calling thread's request (null outside a request).
  static ConnectionStream* current();
  // Called from a handler: close the connection after this response (its body was not read).
  static void close_after_response();

  // Serves one already-connected socket on the calling thread, as an I/O thread does but outside
  // the connection caps, until the client is done or a deadline ends it. The caller closes `fd`.
  // For the HTTP fuzz target (fuzz/fuzz_http.cpp), which feeds requests through a socketpair.
  void serve_socket(int fd);

 private:
  bool process_and_close_socket(socket_t sock) override;
  void serve(ConnectionStream& stream);
  bool stopping() const { return svr_sock_ == INVALID_SOCKET; }
  // Counts a connection from `ip`; false when that address is at its cap.
  bool admit_address(const std::string& ip);
  void release_address(const std::string& ip);

  const ConnectionPolicy policy_;
  Metrics& metrics_;
  std::mutex addresses_mutex_;
  std::map<std::string, unsigned> connections_by_address_;
};

// Answers 503 `overloaded` on `fd` without waiting for the request, then closes it after a short
// bounded drain (so the client reads the answer instead of a reset). At most ~150 ms.
void shed_connection(int fd, const char* reason);

}  // namespace shadowtiles::server
