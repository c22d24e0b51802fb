#include "server/http_service.hpp"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <string_view>

#include "server/connection_queue.hpp"
#include "server/metrics.hpp"

namespace shadowtiles::server {
namespace {

thread_local ConnectionStream* t_current = nullptr;
thread_local bool t_close_after = false;

using Clock = std::chrono::steady_clock;

// Reads and discards what the client sends until EOF, `limit` bytes, `budget` elapsed or `idle`
// without a byte.
void drain(int fd, std::chrono::milliseconds budget, size_t limit,
           std::chrono::milliseconds idle = std::chrono::milliseconds(1 << 30)) {
  const auto until = Clock::now() + budget;
  char scratch[16384];
  size_t total = 0;
  while (total < limit) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(until - Clock::now()).count();
    if (left <= 0) return;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, int(std::min<long long>(left, idle.count()))) <= 0) return;
    const ssize_t n = ::recv(fd, scratch, sizeof scratch, MSG_DONTWAIT);
    if (n <= 0) return;
    total += size_t(n);
  }
}

void send_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n <= 0) return;  // a full send buffer here means a client not reading: give up
    bytes.remove_prefix(size_t(n));
  }
}

std::string raw_error_response(int status, const char* reason_phrase, std::string_view code, std::string_view message) {
  std::string body = R"({"error":")" + std::string(message) + R"(","code":")" + std::string(code) + "\"}";
  return "HTTP/1.1 " + std::to_string(status) + " " + reason_phrase +
         "\r\nContent-Type: application/json\r\nConnection: close\r\nRetry-After: 1\r\nContent-Length: " +
         std::to_string(body.size()) + "\r\n\r\n" + body;
}

}  // namespace

void HttpService::widen_listen_backlog() {
  const socket_t listener = svr_sock_;
  if (listener != INVALID_SOCKET) ::listen(listener, SOMAXCONN);  // Linux: updates the backlog in place
}

ConnectionStream* HttpService::current() { return t_current; }
void HttpService::close_after_response() { t_close_after = true; }

void shed_connection(int fd, const char* reason) {
  // Take what has arrived (closing with unread data sends a reset, which can destroy the answer at
  // the client), answer, then let the client see EOF.
  drain(fd, std::chrono::milliseconds(50), 64 * 1024);
  send_all(fd, raw_error_response(503, "Service Unavailable", "overloaded", reason));
  ::shutdown(fd, SHUT_WR);
  drain(fd, std::chrono::milliseconds(100), 256 * 1024);
  ::close(fd);
}

bool HttpService::admit_address(const std::string& ip) {
  std::lock_guard lock(addresses_mutex_);
  unsigned& count = connections_by_address_[ip];
  if (count >= policy_.max_connections_per_address) {
    if (count == 0) connections_by_address_.erase(ip);
    return false;
  }
  ++count;
  return true;
}

void HttpService::release_address(const std::string& ip) {
  std::lock_guard lock(addresses_mutex_);
  auto it = connections_by_address_.find(ip);
  if (it != connections_by_address_.end() && --it->second == 0) connections_by_address_.erase(it);
}

bool HttpService::process_and_close_socket(socket_t sock) {
  // Responses go out in two writes (headers, body): without TCP_NODELAY each keep-alive response
  // would wait for the client's delayed ACK.
  int one = 1;
  ::setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  switch (ConnectionQueue::lane()) {
    case ConnectionQueue::Lane::shed:
      metrics_.add_rejection(Metrics::Rejection::over_max_connections);
      shed_connection(sock, "too many connections; retry later");
      return true;
    case ConnectionQueue::Lane::drop:
      metrics_.add_rejection(Metrics::Rejection::over_max_connections);
      ::close(sock);
      return true;
    case ConnectionQueue::Lane::io: break;
  }
  ConnectionStream stream(sock, policy_.limits);
  std::string ip;
  if (policy_.max_connections_per_address > 0) {
    ip = stream.remote_ip();
    if (!admit_address(ip)) {
      metrics_.add_rejection(Metrics::Rejection::over_address_cap);
      shed_connection(sock, "too many connections from this address; retry later");
      return true;
    }
  }
  serve(stream);
  if (policy_.max_connections_per_address > 0) release_address(ip);
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return true;
}

void HttpService::serve_socket(int fd) {
  ConnectionStream stream(fd, policy_.limits);
  serve(stream);
}

void HttpService::serve(ConnectionStream& stream) {
  t_current = &stream;
  const unsigned max_requests = policy_.keep_alive_max_count;
  for (unsigned left = max_requests; left > 0 && !stopping(); --left) {
    // A new connection must start its request within the header deadline; an idle keep-alive
    // connection is closed after keep_alive_timeout.
    const auto wait = left == max_requests ? policy_.limits.header_timeout : policy_.keep_alive_timeout;
    if (!stream.wait_for_request(wait, [this] { return stopping(); })) break;
    t_close_after = false;
    bool client_closes = false;
    bool ok = process_request(stream, left == 1 || stopping(), client_closes, nullptr);
    ok = stream.flush() && ok;  // headers of a response without a body
    if (ConnectionStream::Phase expired = stream.expired(); expired != ConnectionStream::Phase::idle) {
      metrics_.add_rejection(stream.over_cap()                            ? Metrics::Rejection::body_too_large
                             : expired == ConnectionStream::Phase::headers ? Metrics::Rejection::header_deadline
                             : expired == ConnectionStream::Phase::body  ? Metrics::Rejection::body_deadline
                                                                         : Metrics::Rejection::response_deadline);
      // httplib answers nothing when the request line itself did not arrive in time.
      if (stream.bytes_written() == 0 && expired != ConnectionStream::Phase::response)
        send_all(stream.socket(), raw_error_response(408, "Request Timeout", "request_timeout",
                                                     "the request did not arrive within the deadline"));
      break;
    }
    if (t_close_after) {
      // Answered before the body was read (an early 413/411): a client still sending its body
      // would get a reset on close, which can destroy the answer before it reads it. Linger like
      // nginx's lingering_close: read and drop what keeps coming, bounded in time and bytes.
      ::shutdown(stream.socket(), SHUT_WR);
      drain(stream.socket(), std::chrono::seconds(2), size_t(64) << 20, std::chrono::milliseconds(250));
      break;
    }
    if (!ok || client_closes) break;
  }
  t_current = nullptr;
}

}  // namespace shadowtiles::server
