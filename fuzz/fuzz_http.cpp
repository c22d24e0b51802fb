// Fuzz target: the whole HTTP service on a real store: httplib's request parsing behind our
// ConnectionStream deadlines, the pre-routing refusals (413/411/431), routing, the query-string,
// JSON-batch and binary-batch parsers, the queries on the store's real tiles and the blob routes.
// Each input is the raw bytes a client sends on one connection (pipelined requests included),
// written into a socketpair whose other end Server::serve_connection serves on this thread.
// Cost per input: one socketpair and two hand-offs to a client thread started once (starting a
// thread per input, under ASan, cost more than serving most requests).
// The store: $SHADOWTILES_FUZZ_STORE (scripts/fuzz.sh builds a small one from a shared scene).
// Invariant: no request a client can send gets a 500 (only a store failing its checks may).
#include <sys/socket.h>
#include <unistd.h>

#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <spdlog/spdlog.h>

#include "fuzz/fuzz_check.hpp"
#include "server/server.hpp"

using namespace shadowtiles;

namespace {

std::unique_ptr<server::Server> g_server;

// Writes the request bytes, half-closes (the server sees EOF after them), reads every answer.
std::string client_side(int fd, const uint8_t* data, size_t size) {
  size_t sent = 0;
  while (sent < size) {
    const ssize_t n = ::send(fd, data + sent, size - sent, MSG_NOSIGNAL);
    if (n <= 0) break;  // the server closed early (an early 413 or 408)
    sent += size_t(n);
  }
  ::shutdown(fd, SHUT_WR);
  std::string answers;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    answers.append(buffer, size_t(n));
  }
  return answers;
}

// The client end of each input's connection, served by one thread for the whole run: run() hands it
// the socket and the bytes, and returns the answers once the server side is done and closed.
class Client {
 public:
  Client() : thread_([this] { loop(); }) {}
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Starts the client side on `fd` (it sends `data`, half-closes, reads to EOF).
  void start(int fd, const uint8_t* data, size_t size) {
    std::lock_guard lock(mutex_);
    fd_ = fd;
    data_ = data;
    size_ = size;
    busy_ = true;
    wake_.notify_one();
  }
  // Waits for the client side to see EOF; its answers.
  std::string finish() {
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [this] { return !busy_; });
    return std::move(answers_);
  }

 private:
  void loop() {
    for (;;) {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return busy_; });
      const int fd = fd_;
      const uint8_t* data = data_;
      const size_t size = size_;
      lock.unlock();
      std::string answers = client_side(fd, data, size);
      lock.lock();
      answers_ = std::move(answers);
      busy_ = false;
      wake_.notify_one();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  int fd_ = -1;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  bool busy_ = false;
  std::string answers_;
  std::thread thread_;  // last: started once the members above exist; never joined (process exit)
};

Client* g_client = nullptr;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);
  const char* store = std::getenv("SHADOWTILES_FUZZ_STORE");
  if (!store || !*store) {
    std::fprintf(stderr, "fuzz_http: set SHADOWTILES_FUZZ_STORE to a store directory (scripts/fuzz.sh does)\n");
    std::exit(2);
  }
  server::ServerConfig config;
  config.port = 0;
  config.threads = 2;
  config.read_timeout_s = 1;
  config.body_timeout_s = 1;
  config.write_timeout_s = 1;
  config.keep_alive_timeout_s = 1;
  config.reload_poll_s = 0;
  config.max_body_bytes = 1 << 20;
  config.max_batch_points = 10000;
  config.cache_bytes = 64 << 20;
  auto bound = server::Server::bind(config);
  if (!bound) {
    std::fprintf(stderr, "fuzz_http: %s\n", bound.error().message.c_str());
    std::exit(2);
  }
  g_server = std::move(*bound);
  if (Status s = g_server->attach_store(store); !s) {
    std::fprintf(stderr, "fuzz_http: %s: %s\n", store, s.error().message.c_str());
    std::exit(2);
  }
  g_client = new Client;  // never destroyed: its thread runs until the process exits
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  int fds[2];
  FUZZ_CHECK(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds) == 0);
  g_client->start(fds[1], data, size);
  g_server->serve_connection(fds[0]);
  ::close(fds[0]);
  const std::string answers = g_client->finish();
  ::close(fds[1]);
  // Every answer's status line; bodies are JSON or blobs, which do not start lines with this.
  for (size_t at = answers.find("HTTP/1.1 "); at != std::string::npos; at = answers.find("\r\nHTTP/1.1 ", at + 1)) {
    const size_t code = answers.find("HTTP/1.1 ", at) + 9;
    if (code + 3 > answers.size()) break;
    if (answers.compare(code, 3, "500") == 0) {
      std::fprintf(stderr, "fuzz_http: a 500 answer:\n%.*s\n", int(std::min<size_t>(answers.size() - at, 600)),
                   answers.data() + at);
      std::abort();
    }
  }
  return 0;
}
