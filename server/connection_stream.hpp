// ConnectionStream: one accepted socket as an httplib::Stream, with the deadlines httplib 0.11 does
// not have. httplib applies its read timeout to each recv, so a client trickling one byte per
// timeout keeps a request open for ever; here every phase of a request has one deadline and a byte
// cap for the whole phase:
//   headers  request line + headers within header_timeout of the request's first byte (at most
//            kMaxHeaderBytes),
//   body     the declared body within body_timeout of the end of the headers (at most the declared
//            length),
//   response the whole response within write_timeout of its first byte.
// A phase over its deadline or cap fails the read or write (httplib then drops the request) and is
// reported by expired(). Reads are buffered across the requests of a keep-alive connection, so
// pipelined requests are not lost. A response's status line and headers (httplib writes them, then
// the body, in two writes) are held back and sent with the body in one sendmsg: one segment and one
// wake-up of the client per small answer instead of two; flush() sends headers held for a response
// without a body.
// Thread safety: one connection, used by one thread at a time.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

#include <poll.h>

#include <httplib.h>

namespace shadowtiles::server {

class ConnectionStream final : public httplib::Stream {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr size_t kMaxHeaderBytes = 64 * 1024;
  static constexpr size_t kMaxHeldBytes = 16 * 1024;  // response headers held for the body
  enum class Phase { idle, headers, body, response };

  struct Limits {
    std::chrono::milliseconds header_timeout{5000};
    std::chrono::milliseconds body_timeout{10000};
    std::chrono::milliseconds write_timeout{5000};
  };

  ConnectionStream(int fd, const Limits& limits);

  // Waits until the next request's first byte is readable (true), for at most `timeout`; false on
  // timeout, EOF, error or when `stop()` turns true (checked every 100 ms). Starts the headers phase.
  template <class StopFn>
  bool wait_for_request(std::chrono::milliseconds timeout, StopFn stop);
  // Ends the headers phase: the body that follows may hold up to `body_bytes` bytes.
  void begin_body(uint64_t body_bytes);
  Phase phase() const { return phase_; }
  // The phase whose deadline or byte cap failed the last request, or idle.
  Phase expired() const { return expired_; }
  // True when the last failure was the phase's byte cap rather than its deadline.
  bool over_cap() const { return over_cap_; }
  // Bytes written for the current request (0: nothing answered yet). Held headers count once sent.
  uint64_t bytes_written() const { return written_; }
  // Sends response headers still held back (a response without a body). Call after each request.
  bool flush();

  bool is_readable() const override;
  bool is_writable() const override;
  ssize_t read(char* ptr, size_t size) override;
  ssize_t write(const char* ptr, size_t size) override;
  void get_remote_ip_and_port(std::string& ip, int& port) const override;
  void get_local_ip_and_port(std::string& ip, int& port) const override;
  socket_t socket() const override { return fd_; }

  // The remote address without the port ("" when unknown).
  std::string remote_ip() const;

 private:
  // Waits for `events` until `deadline`; false on timeout or error.
  bool poll_until(short events, Clock::time_point deadline) const;
  bool fill_buffer();
  void fail_phase() { expired_ = phase_; }
  // Sends `held_` and then [ptr, ptr + size) with as few syscalls as the socket allows; the bytes of
  // `ptr` sent (all of them, or fewer on a deadline or error, then -1 when none).
  ssize_t send_held_and(const char* ptr, size_t size);

  int fd_;
  Limits limits_;
  Phase phase_ = Phase::idle;
  Phase expired_ = Phase::idle;
  bool over_cap_ = false;
  Clock::time_point deadline_{};
  uint64_t phase_budget_ = 0;  // bytes the current read phase may still consume
  uint64_t written_ = 0;
  std::string held_;  // response headers not sent yet
  char buffer_[16 * 1024];
  size_t buffer_begin_ = 0, buffer_end_ = 0;
};

template <class StopFn>
bool ConnectionStream::wait_for_request(std::chrono::milliseconds timeout, StopFn stop) {
  phase_ = Phase::idle;
  expired_ = Phase::idle;
  over_cap_ = false;
  written_ = 0;
  held_.clear();
  const Clock::time_point until = Clock::now() + timeout;
  while (buffer_begin_ == buffer_end_) {
    if (stop()) return false;
    const Clock::time_point now = Clock::now();
    if (now >= until) return false;
    if (poll_until(POLLIN, std::min(until, now + std::chrono::milliseconds(100))) && !fill_buffer()) return false;
  }
  phase_ = Phase::headers;
  deadline_ = Clock::now() + limits_.header_timeout;
  phase_budget_ = kMaxHeaderBytes;
  return true;
}

}  // namespace shadowtiles::server
