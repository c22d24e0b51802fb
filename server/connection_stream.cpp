#include "server/connection_stream.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>

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
  // The first write of a response is its status line and headers: hold them for the body. Not an
  // interim answer (100 Continue), which the client waits for before it sends the body.
  const std::string_view bytes(ptr, size);
  if (written_ == 0 && held_.empty() && size <= kMaxHeldBytes && bytes.ends_with("\r\n\r\n") &&
      !bytes.starts_with("HTTP/1.1 1")) {
    held_.assign(bytes);
    return ssize_t(size);
  }
  return send_held_and(ptr, size);
}

bool ConnectionStream::flush() {
  if (held_.empty()) return true;
  return send_held_and(nullptr, 0) == 0 && held_.empty();
}

ssize_t ConnectionStream::send_held_and(const char* ptr, size_t size) {
  size_t held_sent = 0, done = 0;
  while (held_sent < held_.size() || done < size) {
    iovec parts[2];
    msghdr message{};
    message.msg_iov = parts;
    if (held_sent < held_.size()) parts[message.msg_iovlen++] = {held_.data() + held_sent, held_.size() - held_sent};
    if (done < size) parts[message.msg_iovlen++] = {const_cast<char*>(ptr) + done, size - done};
    const ssize_t n = ::sendmsg(fd_, &message, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      written_ += uint64_t(n);
      const size_t from_held = std::min(size_t(n), held_.size() - held_sent);
      held_sent += from_held;
      done += size_t(n) - from_held;
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && poll_until(POLLOUT, deadline_)) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) fail_phase();
    held_.erase(0, held_sent);
    return done > 0 ? ssize_t(done) : -1;
  }
  held_.clear();
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
