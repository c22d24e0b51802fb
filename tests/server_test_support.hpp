// Shared by the HTTP tests (test_server.cpp: routes and bad input; test_server_blobs.cpp: the blob
// routes; test_serve_process.cpp: the `serve` process, its config and reloads): the bunny test
// store, the server config, a server on its own thread, and encoders of request bodies and checks of
// answers.
#pragma once

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include <atomic>
#include <bit>
#include <map>
#include <mutex>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <thread>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "client/shadow_map.hpp"
#include "codec/store_meta.hpp"
#include "server/routes_blobs.hpp"
#include "server/server.hpp"
#include "store/blob.hpp"
#include "store/lmdb_store.hpp"
#include "store/serving_lock.hpp"
#include "store/tile_key.hpp"
#include "tests/running_server.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles::server_testing {

using nlohmann::json;
using testing::TempDir;

inline constexpr const char* kAllowedOrigin = "https://allowed.example";
inline constexpr const char* kBunny = "bunny/stanford-bunny.obj";

inline BuildConfig bunny_config(const std::filesystem::path& out, std::vector<store::Method> methods) {
  return testing::shared_scene_config({kBunny, UpAxis::y, false}, out, 512, 128, std::move(methods), 135, 45);
}

inline server::ServerConfig test_config() {
  server::ServerConfig config;
  config.port = 0;
  config.max_body_bytes = 2 << 20;
  config.max_batch_points = 20000;
  config.max_pcf = 15;
  config.cors_origins = {kAllowedOrigin};
  config.keep_alive_timeout_s = 1;
  return config;
}

// A server running run() on its own thread; stopped and joined on destruction.
using testing::RunningServer;

inline std::string encode_points(const std::vector<Vec3>& points) {
  std::string body(points.size() * 12, '\0');
  for (size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      uint32_t bits = std::bit_cast<uint32_t>(float(points[i][a]));
      for (int b = 0; b < 4; ++b) body[i * 12 + a * 4 + b] = char(bits >> (8 * b));
    }
  return body;
}

inline std::vector<float> decode_floats(const std::string& body) {
  std::vector<float> out(body.size() / 4);
  for (size_t i = 0; i < out.size(); ++i) {
    uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) bits |= uint32_t(uint8_t(body[i * 4 + b])) << (8 * b);
    out[i] = std::bit_cast<float>(bits);
  }
  return out;
}

inline json points_json(const std::vector<Vec3>& points) {
  json array = json::array();
  for (const Vec3& p : points) array.push_back({p[0], p[1], p[2]});
  return array;
}

inline std::string shadow_url(const Vec3& p, const std::string& extra = "") {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "/v1/shadow?x=%.17g&y=%.17g&z=%.17g", p[0], p[1], p[2]);
  return buffer + extra;
}

// Status and JSON error shape of a 4xx/5xx.
inline void expect_json_error(const httplib::Result& res, int status, const std::string& what) {
  ASSERT_TRUE(res) << what << ": no response";
  EXPECT_EQ(res->status, status) << what << ": " << res->body;
  auto body = json::parse(res->body, nullptr, false);
  ASSERT_TRUE(body.is_object()) << what << ": " << res->body;
  EXPECT_TRUE(body.contains("error") && body["error"].is_string()) << what;
  EXPECT_TRUE(body.contains("code") && body["code"].is_string()) << what;
}

inline std::string strong_etag(uint64_t checksum) {
  std::string etag(1, '"');
  etag += store::checksum_hex(checksum);
  etag += '"';
  return etag;
}

inline uint64_t metric(const std::string& text, const std::string& name) {
  size_t at = text.find("\n" + name + " ");
  if (at == std::string::npos) return 0;
  return std::stoull(text.substr(at + name.size() + 2));
}

// Reads the "listening on http://host:PORT" line of a `shadowtiles serve` child.
inline int read_port(FILE* out) {
  char line[512];
  while (std::fgets(line, sizeof line, out)) {
    std::string text(line);
    size_t at = text.find("listening on http://");
    if (at != std::string::npos) return std::stoi(text.substr(text.rfind(':') + 1));
  }
  return -1;
}

// A `shadowtiles serve ARGS` child process, started through sh so that its pid is known ($$ before
// exec); port is -1 when it never printed its listening line.
struct ServeChild {
  FILE* out = nullptr;
  int pid = -1;
  int port = -1;
};

inline ServeChild start_serve_child(const std::string& args) {
  ServeChild child;
  const std::string command = "sh -c 'echo pid $$; exec " + testing::cli_path().string() + " serve " + args + "' 2>&1";
  child.out = ::popen(command.c_str(), "r");
  if (!child.out) return child;
  if (std::fscanf(child.out, "pid %d\n", &child.pid) != 1) return child;
  child.port = read_port(child.out);
  return child;
}

// Reads the child's remaining output into `rest` and waits for it; returns its waitpid status.
inline int finish_serve_child(ServeChild& child, std::string* rest) {
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, child.out)) *rest += buffer;
  const int status = ::pclose(child.out);
  child.out = nullptr;
  return status;
}

}  // namespace shadowtiles::server_testing
