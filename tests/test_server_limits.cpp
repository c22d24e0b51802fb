// The server under slow and hostile clients, on loopback with a real store (bunny 512^2, raw + mh):
// connections that trickle their headers or stall their body hold I/O threads but never the query
// workers, so /healthz and a point query still answer well inside the read timeout while
// max_connections - 2 such clients are connected; each phase has a deadline (408); a declared body
// over the limit, a chunked body and a batch over the cost limit are refused at once (413/411); a
// full server or a busy address gets a quick 503.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "builder/build_job.hpp"
#include "client/shadow_map.hpp"
#include "server/server.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// A raw TCP client: sends exactly what it is told, so it can misbehave.
class RawClient {
 public:
  explicit RawClient(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(uint16_t(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  }
  ~RawClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  bool connected() const { return connected_; }
  bool send(const std::string& bytes) { return ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) == ssize_t(bytes.size()); }
  // Everything the server sends until it closes or `timeout` passes.
  std::string read_until_close(std::chrono::milliseconds timeout) {
    std::string out;
    const auto until = Clock::now() + timeout;
    char buffer[4096];
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
      if (left <= 0) break;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, int(left)) <= 0) break;
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      out.append(buffer, size_t(n));
    }
    return out;
  }
  // True when the server has closed its side (EOF) within `timeout`, after any answer.
  bool closed_within(std::chrono::milliseconds timeout) {
    read_until_close(timeout);
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 0) <= 0) return false;
    char c;
    return ::recv(fd_, &c, 1, MSG_DONTWAIT) == 0;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

int status_of(const std::string& response) {
  int status = 0;
  return std::sscanf(response.c_str(), "HTTP/1.1 %d", &status) == 1 ? status : 0;
}

class ServerLimitsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir;
    store_ = dir_->path() / "bunny.store";
    BuildConfig config;
    config.scene_path = testing::shared_scene("bunny/stanford-bunny.obj");
    config.store_path = store_;
    config.resolution = 512;
    config.tile_size = 128;
    config.load.up = UpAxis::y;
    config.light_direction = *light_direction_from_sun(135, 45, UpAxis::y);
    config.methods = {store::Method::raw, store::Method::mh};
    auto built = run_build(config);
    ASSERT_TRUE(built.ok()) << built.error().message;
  }
  static void TearDownTestSuite() { delete dir_; }

  struct Running {
    std::unique_ptr<server::Server> server;
    std::thread thread;
    ~Running() {
      if (server) server->stop();
      if (thread.joinable()) thread.join();
    }
    int port() const { return server->port(); }
  };
  static server::ServerConfig base_config() {
    server::ServerConfig config;
    config.port = 0;
    config.threads = 2;
    config.max_connections = 16;
    config.read_timeout_s = 5;
    config.body_timeout_s = 3;
    config.keep_alive_timeout_s = 5;
    config.max_body_bytes = 1 << 20;
    config.max_batch_points = 50000;
    config.max_batch_cost = 100000;
    config.reload_poll_s = 0;
    return config;
  }
  static std::unique_ptr<Running> start(const server::ServerConfig& config) {
    auto running = std::make_unique<Running>();
    auto bound = server::Server::bind(config);
    EXPECT_TRUE(bound.ok()) << bound.error().message;
    if (!bound.ok()) return running;
    running->server = std::move(*bound);
    EXPECT_TRUE(running->server->attach_store(store_).ok());
    running->thread = std::thread([s = running->server.get()] { EXPECT_TRUE(s->run().ok()); });
    httplib::Client probe("127.0.0.1", running->port());
    for (int i = 0; i < 300 && !probe.Get("/healthz"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return running;
  }
  // Status of one request on a new connection, and how long it took.
  static std::pair<int, double> timed_get(int port, const std::string& path) {
    httplib::Client c("127.0.0.1", port);
    c.set_read_timeout(10, 0);
    auto start = Clock::now();
    auto res = c.Get(path);
    return {res ? res->status : -1, seconds_since(start)};
  }

  static inline testing::TempDir* dir_ = nullptr;
  static inline std::filesystem::path store_;
};

// The stall: clients that send a request line and never finish their headers, and clients
// that declare a body and never send it, fill all but two connection slots; queries still answer.
TEST_F(ServerLimitsTest, SlowClientsNeverStarveQueries) {
  auto config = base_config();
  auto running = start(config);
  const int port = running->port();
  const unsigned slow = config.max_connections - 2;
  std::vector<std::unique_ptr<RawClient>> clients;
  for (unsigned i = 0; i < slow; ++i) {
    clients.push_back(std::make_unique<RawClient>(port));
    ASSERT_TRUE(clients.back()->connected());
    if (i % 2 == 0) ASSERT_TRUE(clients.back()->send("GET /healthz HTTP/1.1\r\nHost: x\r\n"));  // headers never end
    else
      ASSERT_TRUE(clients.back()->send("POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                                       "Content-Length: 1000\r\n\r\n{\"points\""));  // body stalls
  }
  // Header tricklers keep sending one byte every 200 ms: a per-read timeout would never fire.
  std::atomic<bool> trickling{true};
  std::thread trickler([&] {
    while (trickling) {
      for (unsigned i = 0; i < slow; i += 2) clients[i]->send("X");
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // every slow client is being served
  double worst = 0;
  for (int round = 0; round < 10; ++round) {
    auto [health, health_s] = timed_get(port, "/healthz");
    auto [point, point_s] = timed_get(port, "/v1/shadow?x=0&y=0.1&z=0");
    EXPECT_EQ(health, 200);
    EXPECT_EQ(point, 200);
    worst = std::max({worst, health_s, point_s});
  }
  trickling = false;
  trickler.join();
  std::printf("slow clients held: %u of %u connections; worst /healthz or point query: %.1f ms (read timeout %u s)\n",
              slow, config.max_connections, worst * 1e3, config.read_timeout_s);
  EXPECT_LT(worst, 1.0) << "well inside the read timeout";

  // Every slow client is cut off at its deadline with 408: headers within read_timeout_s of their
  // first byte, the body within body_timeout_s of the headers.
  const auto deadline = std::chrono::seconds(config.read_timeout_s + 3);
  for (unsigned i = 0; i < slow; ++i) {
    std::string answer = clients[i]->read_until_close(deadline);
    EXPECT_EQ(status_of(answer), 408) << "client " << i << ": " << answer.substr(0, 80);
  }
}

TEST_F(ServerLimitsTest, OversizedBodiesAreRefusedAtOnce) {
  auto running = start(base_config());
  const int port = running->port();
  // The case: twelve requests announce 99999999999 bytes and send nothing.
  std::vector<std::unique_ptr<RawClient>> liars;
  for (int i = 0; i < 12; ++i) {
    liars.push_back(std::make_unique<RawClient>(port));
    ASSERT_TRUE(liars.back()->send("POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                                   "Content-Length: 99999999999\r\n\r\n"));
  }
  auto start_time = Clock::now();
  for (auto& liar : liars) {
    std::string answer = liar->read_until_close(std::chrono::seconds(3));
    EXPECT_EQ(status_of(answer), 413) << answer.substr(0, 120);
    EXPECT_NE(answer.find("payload_too_large"), std::string::npos);
  }
  EXPECT_LT(seconds_since(start_time), 1.0) << "413 at once, not after a read timeout";
  auto [point, point_s] = timed_get(port, "/v1/shadow?x=0&y=0.1&z=0");
  EXPECT_EQ(point, 200);
  EXPECT_LT(point_s, 1.0);

  // With Expect: 100-continue the refusal comes instead of the 100.
  RawClient expecting(port);
  ASSERT_TRUE(expecting.send("POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                             "Expect: 100-continue\r\nContent-Length: 5000000\r\n\r\n"));
  EXPECT_EQ(status_of(expecting.read_until_close(std::chrono::seconds(3))), 413);

  // A chunked body has no size up front: 411.
  RawClient chunked(port);
  ASSERT_TRUE(chunked.send("POST /v1/shadow HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                           "Transfer-Encoding: chunked\r\n\r\n5\r\nhello\r\n"));
  EXPECT_EQ(status_of(chunked.read_until_close(std::chrono::seconds(3))), 411);

  // Headers without end beyond the 64 KiB cap: cut off, not buffered for ever.
  RawClient endless(port);
  ASSERT_TRUE(endless.send("GET /healthz HTTP/1.1\r\n"));
  std::string filler = "X-Filler: " + std::string(1000, 'a') + "\r\n";
  for (int i = 0; i < 80 && endless.send(filler); ++i) {
  }
  std::string answer = endless.read_until_close(std::chrono::seconds(3));
  EXPECT_TRUE(answer.empty() || status_of(answer) == 431) << answer.substr(0, 80);
  EXPECT_TRUE(endless.closed_within(std::chrono::seconds(3)));
}

TEST_F(ServerLimitsTest, BatchesAreAdmittedByCost) {
  auto config = base_config();  // max_batch_cost 100000
  auto running = start(config);
  httplib::Client c("127.0.0.1", running->port());
  // 20000 points x 3^2 = 180000 > 100000: refused on the headers, before the body.
  std::string body(20000 * 12, '\0');
  auto costly = c.Post("/v1/shadow?pcf=3", body, "application/octet-stream");
  ASSERT_TRUE(costly);
  EXPECT_EQ(costly->status, 413);
  EXPECT_EQ(json::parse(costly->body)["code"], "batch_too_costly");
  auto fine = c.Post("/v1/shadow?pcf=1", body, "application/octet-stream");  // 20000 x 1
  ASSERT_TRUE(fine);
  EXPECT_EQ(fine->status, 200);
  EXPECT_EQ(fine->body.size(), 20000u * 4);
  // JSON: the cost is known once parsed. 1000 points x 15^2 = 225000.
  json points = json::array();
  for (int i = 0; i < 1000; ++i) points.push_back({0.0, 0.1, 0.0});
  auto json_costly = c.Post("/v1/shadow", json{{"points", points}, {"pcf", 15}}.dump(), "application/json");
  ASSERT_TRUE(json_costly);
  EXPECT_EQ(json_costly->status, 413);
  EXPECT_EQ(json::parse(json_costly->body)["code"], "batch_too_costly");
  auto json_fine = c.Post("/v1/shadow", json{{"points", points}, {"pcf", 9}}.dump(), "application/json");
  ASSERT_TRUE(json_fine);
  EXPECT_EQ(json_fine->status, 200);
}

TEST_F(ServerLimitsTest, FullServerAnswers503AtOnce) {
  auto config = base_config();
  config.max_connections = 4;
  config.threads = 2;
  auto running = start(config);
  const int port = running->port();
  // Four idle keep-alive clients hold every connection slot.
  std::vector<std::unique_ptr<httplib::Client>> holders;
  for (int i = 0; i < 4; ++i) {
    holders.push_back(std::make_unique<httplib::Client>("127.0.0.1", port));
    holders.back()->set_keep_alive(true);
    auto res = holders.back()->Get("/healthz");
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  auto [status, took] = timed_get(port, "/v1/meta");
  EXPECT_EQ(status, 503);
  EXPECT_LT(took, 1.0) << "a quick 503, never a hang";
  holders.clear();
  int after = -1;
  for (int i = 0; i < 300 && after != 200; ++i) {
    after = timed_get(port, "/healthz").first;
    if (after != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(after, 200) << "slots free again once the holders leave";
}

TEST_F(ServerLimitsTest, PerAddressCap) {
  auto config = base_config();
  config.max_connections_per_address = 2;
  auto running = start(config);
  const int port = running->port();
  std::vector<std::unique_ptr<httplib::Client>> holders;
  for (int i = 0; i < 2; ++i) {
    holders.push_back(std::make_unique<httplib::Client>("127.0.0.1", port));
    holders.back()->set_keep_alive(true);
    int status = -1;
    for (int k = 0; k < 300 && status != 200; ++k) {  // the start-up probe may still hold a slot
      auto res = holders.back()->Get("/healthz");
      status = res ? res->status : -1;
      if (status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_EQ(status, 200);
  }
  auto [status, took] = timed_get(port, "/healthz");
  EXPECT_EQ(status, 503);
  EXPECT_LT(took, 1.0);
  httplib::Client metrics_client("127.0.0.1", port);
  holders.pop_back();
  int after = -1;
  for (int i = 0; i < 300 && after != 200; ++i) {
    after = timed_get(port, "/healthz").first;
    if (after != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(after, 200);
}

}  // namespace
}  // namespace shadowtiles
