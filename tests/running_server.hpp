// A real shadowtiles server on loopback, on its own thread, for tests: bound to an ephemeral port,
// answering /healthz before the constructor returns (so stop() cannot race the listener's start);
// stop() or the destructor stops and joins it.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include <httplib.h>

#include "server/server.hpp"

namespace shadowtiles::testing {

// Port 0 (ephemeral), 1 s keep-alive so idle test clients free their threads, 20,000-point batches.
inline server::ServerConfig loopback_server_config() {
  server::ServerConfig config;
  config.port = 0;
  config.keep_alive_timeout_s = 1;
  config.max_batch_points = 20000;
  return config;
}

class RunningServer {
 public:
  // Serves `store_dir` when given (else no store: /healthz only until one is attached).
  RunningServer(const server::ServerConfig& config, const std::filesystem::path* store_dir) {
    auto bound = server::Server::bind(config);
    EXPECT_TRUE(bound.ok()) << bound.error().message;
    server_ = std::move(*bound);
    if (store_dir) {
      Status s = server_->attach_store(*store_dir);
      EXPECT_TRUE(s.ok()) << s.error().message;
    }
    thread_ = std::thread([this] { EXPECT_TRUE(server_->run().ok()); });
    httplib::Client probe("127.0.0.1", port());
    for (int i = 0; i < 200 && !probe.Get("/healthz"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  explicit RunningServer(const std::filesystem::path& store_dir)
      : RunningServer(loopback_server_config(), &store_dir) {}
  ~RunningServer() { stop(); }
  RunningServer(const RunningServer&) = delete;
  RunningServer& operator=(const RunningServer&) = delete;

  void stop() {
    if (!thread_.joinable()) return;
    server_->stop();
    thread_.join();
  }
  int port() const { return server_->port(); }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port()); }
  server::Server& server() { return *server_; }
  // A keep-alive client with a 20 s read timeout.
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port());
    c.set_keep_alive(true);
    c.set_tcp_nodelay(true);
    c.set_read_timeout(20, 0);
    return c;
  }

 private:
  std::unique_ptr<server::Server> server_;
  std::thread thread_;
};

}  // namespace shadowtiles::testing
