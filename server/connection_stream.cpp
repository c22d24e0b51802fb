#include "server/connection_stream.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace shadowtiles::server {
namespace {

void address_of(const sockaddr_storage& addr, std::string& ip, int& port) {
  char text[INET6_ADDRSTRLEN] = {};
  if (addr.ss_family == AF_INET) {
    const auto& in = reinterpret_cast<const sockaddr_in&>(addr);
    inet_ntop(AF_INET, &in.sin_addr, text, sizeof text);
    port = ntohs(in.sin_port);
  } else if (addr.ss_family == AF_INET6) {
    const auto& in6 = reinterpret_cast<const sockaddr_in6&>(addr);
    inet_ntop(AF_INET6, &in6.sin6_addr, text, sizeof text);
    port = ntohs(in6.sin6_port);
  }
  ip = text;
}

}  // namespace

ConnectionStream::ConnectionStream(int fd, const Limits& limits) : fd_(fd), limits_(limits) {}

bool ConnectionStream::poll_until(short events, Clock::time_point deadline) const {
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd_, events, 0};
    const int ready = ::poll(&p, 1, int(std::min<long long>(left, 1 << 30)));
    if (ready > 0) return true;  // readable/writable, or an error the next recv/send reports
    if (ready == 0) return false;
    if (errno != EINTR) return false;
  }
}

bool ConnectionStream::fill_buffer() {
  for (;;) {
    const ssize_t n = ::recv(fd_, buffer_, sizeof buffer_, 0);
    if (n > 0) {
      buffer_begin_ = 0;
      buffer_end_ = size_t(n);
      return true;
    }
    if (n < 0 && errno == EINTR) continue;
    return false;  // EOF or error
  }
}

void ConnectionStream::begin_body(uint64_t body_bytes) {
  phase_ = Phase::body;
  deadline_ = Clock::now() + limits_.body_timeout;
  phase_budget_ = body_bytes;
}

bool ConnectionStream::is_readable() const {
  return buffer_begin_ != buffer_end_ || poll_until(POLLIN, deadline_);
}

bool ConnectionStream::is_writable() const {
  return poll_until(POLLOUT, phase_ == Phase::response ? deadline_ : Clock::now() + limits_.write_timeout);
}

ssize_t ConnectionStream::read(char* ptr, size_t size) {
  if (phase_ != Phase::headers && phase_ != Phase::body) return -1;
  if (size == 0) return 0;
  if (phase_budget_ == 0) {
    over_cap_ = true;
    fail_phase();
    return -1;
  }
  if (buffer_begin_ == buffer_end_) {
    if (!poll_until(POLLIN, deadline_)) {
      fail_phase();
      return -1;
    }
    if (!fill_buffer()) return 0;  // the client closed (or reset) the connection
  }
  const size_t n = std::min({size, buffer_end_ - buffer_begin_, size_t(std::min<uint64_t>(phase_budget_, SIZE_MAX))});
  std::memcpy(ptr, buffer_ + buffer_begin_, n);
  buffer_begin_ += n;
  phase_budget_ -= n;
  return ssize_t(n);
}

ssize_t ConnectionStream::write(const char* ptr, size_t size) {
  if (phase_ != Phase::response) {
    phase_ = Phase::response;
    deadline_ = Clock::now() + limits_.write_timeout;
  }
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::send(fd_, ptr + done, size - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      done += size_t(n);
      written_ += uint64_t(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && poll_until(POLLOUT, deadline_)) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) fail_phase();
    return done > 0 ? ssize_t(done) : -1;
  }
  return ssize_t(done);
}

void ConnectionStream::get_remote_ip_and_port(std::string& ip, int& port) const {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  ip.clear();
  port = 0;
  if (::getpeername(fd_, reinterpret_cast<sockaddr*>(&addr), &len) == 0) address_of(addr, ip, port);
}

void ConnectionStream::get_local_ip_and_port(std::string& ip, int& port) const {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  ip.clear();
  port = 0;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len) == 0) address_of(addr, ip, port);
}

std::string ConnectionStream::remote_ip() const {
  std::string ip;
  int port = 0;
  get_remote_ip_and_port(ip, port);
  return ip;
}

}  // namespace shadowtiles::server
