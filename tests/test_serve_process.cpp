// The `shadowtiles serve` process and the server's lifecycle: strict config parsing and overrides,
// the CLI's config flags and SIGTERM drain, the config's store key, and reloads that swap builds
// (also under load, in-process and by SIGHUP to the real process, never mixing two builds in one answer).
#include <gtest/gtest.h>

#include <atomic>

#include "tests/server_test_support.hpp"

namespace shadowtiles {
namespace {

// ln -sfn: a new link renamed over the old one, so readers see one target or the other.
void repoint(const std::filesystem::path& link, const std::filesystem::path& target) {
  const auto next = link.string() + ".next";
  std::filesystem::create_directory_symlink(target, next);
  std::filesystem::rename(next, link);
}

using namespace server_testing;

TEST(ServerConfig, StrictParsingAndOverrides) {
  auto config = server::ServerConfig::from_json(json{{"port", 0}, {"threads", 4}, {"cors_origins", {"https://a.example"}}});
  ASSERT_TRUE(config.ok()) << config.error().message;
  EXPECT_EQ(config->threads, 4u);
  EXPECT_EQ(config->host, "127.0.0.1");
  for (const json& bad : {json{{"prot", 8080}}, json{{"port", 70000}}, json{{"port", -1}}, json{{"port", "80"}},
                          json{{"threads", 0}}, json{{"threads", 2.5}}, json{{"max_pcf", 4}}, json{{"max_pcf", 99}},
                          json{{"cors_origins", "https://a.example"}}, json{{"cors_origins", {"*"}}},
                          json{{"read_timeout_s", 0}}, json{{"max_connections", 1}}, json{{"max_pinned_sends", 101}},
                          json{{"blob_recheck_ms", 3600001}},
                          json::array()}) {
    auto parsed = server::ServerConfig::from_json(bad);
    EXPECT_FALSE(parsed.ok()) << bad.dump();
    if (!parsed.ok()) {
      EXPECT_EQ(parsed.error().code, ErrorCode::invalid_input);
    }
  }
  auto shipped = server::ServerConfig::load(std::filesystem::path(SHADOWTILES_SOURCE_DIR) / "config" / "serve.json");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  EXPECT_EQ(shipped->to_json(), server::ServerConfig{}.to_json()) << "config/serve.json documents the defaults";
}


TEST(ServeCommand, ConfigFlagsAndSigtermDrain) {
  TempDir dir;
  auto store_dir = dir.path() / "s";
  ASSERT_TRUE(run_build(bunny_config(store_dir, {store::Method::raw})).ok());
  const std::string cli = testing::cli_path().string();

  std::string output;
  ASSERT_EQ(testing::run_command(cli + " serve " + store_dir.string() + " --print-config --port 9999 --threads 3", &output), 0)
      << output;
  auto printed = json::parse(output.substr(output.find('{')));
  EXPECT_EQ(printed["port"], 9999);
  EXPECT_EQ(printed["threads"], 3);

  std::ofstream(dir.path() / "bad.json") << R"({"port": 1, "unknown_key": true})";
  output.clear();
  EXPECT_EQ(testing::run_command(cli + " serve " + store_dir.string() + " --config " + (dir.path() / "bad.json").string(), &output), 2);
  EXPECT_NE(output.find("unknown_key"), std::string::npos) << output;
  output.clear();
  EXPECT_EQ(testing::run_command(cli + " serve " + (dir.path() / "missing").string() + " --port 0", &output), 2) << output;

  // The child's pid is the shell's ($$) because of exec.
  ServeChild child = start_serve_child(store_dir.string() + " --port 0 --config " + SHADOWTILES_SOURCE_DIR +
                                       "/config/serve.json");
  ASSERT_NE(child.out, nullptr);
  ASSERT_GT(child.pid, 0);
  const int pid = child.pid, port = child.port;
  ASSERT_GT(port, 0);
  httplib::Client client("127.0.0.1", port);
  auto health = client.Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  // A batch in flight while SIGTERM arrives still completes (500k points take ~0.1 s to answer).
  // Its connection is opened and served first, so the batch cannot arrive after the listener closed.
  // SIGTERM goes once the client has handed the body's last piece to the socket: the server is then
  // reading this request (6 MB do not fit in the socket's buffers). A fixed sleep instead raced on a
  // loaded machine: a request not yet begun on an idle keep-alive connection is closed by the drain,
  // as HTTP allows, and the client's write failed.
  const std::string body = encode_points(std::vector<Vec3>(500000, Vec3{0, 0.1, 0}));
  httplib::Client keep("127.0.0.1", port);
  keep.set_keep_alive(true);
  ASSERT_TRUE(keep.Get("/healthz"));
  std::atomic<bool> body_sent{false};
  std::thread batch([&] {
    auto res = keep.Post(
        "/v1/shadow", body.size(),
        [&](size_t offset, size_t length, httplib::DataSink& sink) {
          const size_t piece = std::min<size_t>(length, 64 * 1024);
          if (!sink.write(body.data() + offset, piece)) return false;
          if (offset + piece == body.size()) body_sent = true;
          return true;
        },
        "application/octet-stream");
    body_sent = true;  // also on failure: the main thread stops waiting
    ASSERT_TRUE(res) << httplib::to_string(res.error());
    EXPECT_EQ(res->status, 200);
    EXPECT_EQ(res->body.size(), 500000u * 4);
  });
  for (int waited = 0; !body_sent && waited < 30000; ++waited) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  batch.join();
  std::string rest;
  const int status = finish_serve_child(child, &rest);
  ASSERT_TRUE(WIFEXITED(status)) << rest;
  EXPECT_EQ(WEXITSTATUS(status), 0) << rest;
  EXPECT_NE(rest.find("stopped on signal"), std::string::npos) << rest;
}

// The config's "store" key names the store, so a service unit passes only --config; without it
// (and without the argument) serve refuses to start.
TEST(ServeCommand, StoreKeyOfTheConfig) {
  TempDir dir;
  auto store_dir = dir.path() / "s";
  ASSERT_TRUE(run_build(bunny_config(store_dir, {store::Method::raw})).ok());
  const std::string cli = testing::cli_path().string();
  std::ofstream(dir.path() / "none.json") << R"({"port": 0})";
  std::string output;
  EXPECT_EQ(testing::run_command(cli + " serve --config " + (dir.path() / "none.json").string(), &output), 2);
  EXPECT_NE(output.find("\"store\" key"), std::string::npos) << output;

  std::ofstream(dir.path() / "unit.json") << json{{"store", store_dir.string()}, {"port", 0}}.dump();
  ServeChild child = start_serve_child("--config " + (dir.path() / "unit.json").string());
  ASSERT_NE(child.out, nullptr);
  ASSERT_GT(child.pid, 0);
  const int pid = child.pid, port = child.port;
  ASSERT_GT(port, 0);
  auto health = httplib::Client("127.0.0.1", port).Get("/healthz");
  ::kill(pid, SIGTERM);
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  std::string rest;
  const int status = finish_serve_child(child, &rest);
  ASSERT_TRUE(WIFEXITED(status)) << rest;
  EXPECT_EQ(WEXITSTATUS(status), 0) << rest;
}


// Swapping builds (docs/architecture.md §9): the server follows the store path (a symlink repointed
// atomically), publishes the new build without a restart, keeps builders out of the directory it
// serves, and keeps serving the current build when the path holds no complete build.
TEST(ServerReload, SwapsToTheBuildTheStorePathPointsAt) {
  TempDir dir;
  const auto a = dir.path() / "a.store", b = dir.path() / "b.store";
  ASSERT_TRUE(run_build(bunny_config(a, {store::Method::raw})).ok());
  BuildConfig config_b = bunny_config(b, {store::Method::raw, store::Method::mh});
  config_b.light_direction = *light_direction_from_sun(200, 60, UpAxis::y);
  ASSERT_TRUE(run_build(config_b).ok());
  std::filesystem::copy(b, dir.path() / "b-reference.store", std::filesystem::copy_options::recursive);
  auto reference_b = ShadowMap::open(dir.path() / "b-reference.store");
  ASSERT_TRUE(reference_b.ok());

  const auto current = dir.path() / "current";
  std::filesystem::create_directory_symlink(a, current);
  auto config = test_config();
  config.reload_poll_s = 1;
  RunningServer running(config, &current);
  auto cli = running.client();
  auto served_build = [&] {
    auto res = cli.Get("/v1/meta");
    return res && res->status == 200 ? json::parse(res->body)["shadow"]["build_id"].get<std::string>() : "";
  };
  const std::string id_a = served_build();
  ASSERT_FALSE(id_a.empty());
  EXPECT_EQ(id_a, running.server().build_id());

  EXPECT_FALSE(store::ServingLock::acquire(a, store::ServingLock::Kind::build).ok()) << "served: no builds";
  auto rebuilt = run_build(bunny_config(a, {store::Method::raw}));
  ASSERT_FALSE(rebuilt.ok()) << "a build refuses a served store";
  EXPECT_NE(rebuilt.error().message.find("being served"), std::string::npos) << rebuilt.error().message;
  EXPECT_TRUE(store::ServingLock::acquire(b, store::ServingLock::Kind::build).ok());
  auto unchanged = running.server().reload();
  ASSERT_TRUE(unchanged.ok()) << unchanged.error().message;
  EXPECT_FALSE(*unchanged);

  repoint(current, b);  // picked up by the poller, no SIGHUP needed
  std::string id_b = id_a;
  for (int i = 0; i < 100 && id_b == id_a; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    id_b = served_build();
  }
  ASSERT_NE(id_b, id_a);
  EXPECT_EQ(id_b, reference_b->get()->meta().config_hash);
  expect_json_error(cli.Get("/v1/builds/" + id_a + "/tiles/raw/2/1/1"), 404, "the replaced build");
  auto tile = cli.Get("/v1/builds/" + id_b + "/tiles/raw/2/1/1");
  ASSERT_TRUE(tile);
  EXPECT_TRUE(tile->status == 200 || tile->status == 204) << tile->status;
  auto top = cli.Get("/v1/skiplist?method=mh");
  ASSERT_TRUE(top);
  EXPECT_EQ(top->status, 200) << "the new build's methods are served";
  LoadOptions load;
  load.up = UpAxis::y;
  auto scene = load_scene(testing::shared_scene(kBunny), load);
  ASSERT_TRUE(scene.ok());
  for (const Receiver& r : sample_receivers(*scene, 200, 3)) {
    auto res = cli.Get(shadow_url(r.position));
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200);
    auto expected = reference_b->get()->query(r.position, store::Method::raw);
    ASSERT_TRUE(expected.ok());
    EXPECT_EQ(json::parse(res->body)["lit"].get<double>(), expected->lit ? 1.0 : 0.0);
  }
  EXPECT_TRUE(store::ServingLock::acquire(a, store::ServingLock::Kind::build).ok())
      << "the old build is closed once its requests are done";

  const auto empty = dir.path() / "empty";
  std::filesystem::create_directory(empty);
  repoint(current, empty);
  EXPECT_FALSE(running.server().reload().ok()) << "no build there";
  EXPECT_EQ(served_build(), id_b) << "the current build stays served";
}


// Two bunny stores lit from different suns, each one's binary answer to the same batch, and the
// store link `current` pointing at a.
struct TwoBuilds {
  std::filesystem::path a, b, current;
  std::vector<Vec3> points;
  std::map<std::string, std::string> expected;  // build id -> the binary answer of the whole batch
};

void make_two_builds(const std::filesystem::path& dir, TwoBuilds* builds) {
  builds->a = dir / "a.store";
  builds->b = dir / "b.store";
  ASSERT_TRUE(run_build(bunny_config(builds->a, {store::Method::raw})).ok());
  BuildConfig config_b = bunny_config(builds->b, {store::Method::raw});
  config_b.light_direction = *light_direction_from_sun(200, 60, UpAxis::y);
  ASSERT_TRUE(run_build(config_b).ok());
  LoadOptions load;
  load.up = UpAxis::y;
  auto scene = load_scene(testing::shared_scene(kBunny), load);
  ASSERT_TRUE(scene.ok());
  for (const Receiver& r : sample_receivers(*scene, 512, 11))
    builds->points.push_back({double(float(r.position[0])), double(float(r.position[1])), double(float(r.position[2]))});
  for (const auto& dir_of_build : {builds->a, builds->b}) {
    auto map = ShadowMap::open(dir_of_build);
    ASSERT_TRUE(map.ok());
    std::string body;
    for (const Vec3& p : builds->points) {
      auto answer = (*map)->query(p, store::Method::raw);
      ASSERT_TRUE(answer.ok());
      const float lit = answer->lit ? 1.0f : 0.0f;
      body.append(reinterpret_cast<const char*>(&lit), 4);
    }
    builds->expected[(*map)->meta().config_hash] = body;
  }
  ASSERT_EQ(builds->expected.size(), 2u);
  ASSERT_NE(builds->expected.begin()->second, builds->expected.rbegin()->second)
      << "the two builds must answer differently";
  builds->current = dir / "current";
  std::filesystem::create_directory_symlink(builds->a, builds->current);
}

// 4 keep-alive clients send the batch without pause to the server on `port` while `swap` repoints
// and reloads mid-load. No request may fail, every answer names its build (X-Shadowtiles-Build), and
// every batch equals that one build's answer in full: never a mix within one batch.
void expect_swap_under_load_loses_nothing(int port, const TwoBuilds& builds, const std::function<void()>& swap,
                                          const char* how) {
  const std::string body = encode_points(builds.points);
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::map<std::string, int> answers_by_build;
  int failed = 0, mixed = 0;
  std::vector<std::thread> clients;
  for (int c = 0; c < 4; ++c)
    clients.emplace_back([&] {
      httplib::Client cli("127.0.0.1", port);
      cli.set_keep_alive(true);
      cli.set_read_timeout(20, 0);
      while (!stop.load()) {
        auto res = cli.Post("/v1/shadow?method=raw", body, "application/octet-stream");
        std::lock_guard lock(mutex);
        if (!res || res->status != 200) {
          ++failed;
          continue;
        }
        const std::string build = res->get_header_value("X-Shadowtiles-Build");
        auto it = builds.expected.find(build);
        if (it == builds.expected.end() || it->second != res->body) ++mixed;
        ++answers_by_build[build];
      }
    });
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  swap();
  // Until the new build answers (a signal is handled asynchronously), then a while longer.
  for (int i = 0; i < 100; ++i) {
    {
      std::lock_guard lock(mutex);
      if (answers_by_build.size() == 2) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  stop = true;
  for (auto& t : clients) t.join();
  EXPECT_EQ(failed, 0) << "requests lost during the swap";
  EXPECT_EQ(mixed, 0) << "answers that are not exactly one build's";
  ASSERT_EQ(answers_by_build.size(), 2u) << "both builds answered";
  int total = 0;
  for (const auto& [build, n] : answers_by_build) {
    EXPECT_GT(n, 0) << build;
    total += n;
  }
  std::printf("swap under load (%s): %d batches of %zu points from 4 clients, %d failed, %d mixed\n", how, total,
              builds.points.size(), failed, mixed);
}

// A swap under load (issue 18), in-process: the store path is repointed and Server::reload runs
// (what SIGHUP does in `shadowtiles serve`).
TEST(ServerReload, SwapUnderLoadLosesNoRequestAndNeverMixesBuilds) {
  TempDir dir;
  TwoBuilds builds;
  make_two_builds(dir.path(), &builds);
  if (HasFatalFailure()) return;
  const auto& current = builds.current;
  auto config = test_config();
  config.reload_poll_s = 0;  // only the explicit reload below swaps
  RunningServer running(config, &current);
  expect_swap_under_load_loses_nothing(running.port(), builds, [&] {
    repoint(current, builds.b);
    auto swapped = running.server().reload();
    ASSERT_TRUE(swapped.ok()) << swapped.error().message;
    EXPECT_TRUE(*swapped);
  }, "Server::reload");
}

// The same with the real process and the real signal: `shadowtiles serve --config` (reload on SIGHUP
// only), the link repointed with rename, then `kill -HUP`.
TEST(ServerReload, SighupToTheServeProcessSwapsUnderLoadLosingNothing) {
  TempDir dir;
  TwoBuilds builds;
  make_two_builds(dir.path(), &builds);
  if (HasFatalFailure()) return;
  const auto& current = builds.current;
  std::ofstream(dir.path() / "serve.json")
      << json{{"store", current.string()}, {"port", 0}, {"reload_poll_s", 0}, {"keep_alive_timeout_s", 1}}.dump();
  ServeChild child = start_serve_child("--config " + (dir.path() / "serve.json").string());
  ASSERT_NE(child.out, nullptr);
  ASSERT_GT(child.pid, 0);
  ASSERT_GT(child.port, 0);
  expect_swap_under_load_loses_nothing(child.port, builds, [&] {
    repoint(current, builds.b);
    ASSERT_EQ(::kill(child.pid, SIGHUP), 0);
  }, "SIGHUP to shadowtiles serve");
  ASSERT_EQ(::kill(child.pid, SIGTERM), 0);
  std::string rest;
  const int status = finish_serve_child(child, &rest);
  ASSERT_TRUE(WIFEXITED(status)) << rest;
  EXPECT_EQ(WEXITSTATUS(status), 0) << rest;
  EXPECT_NE(rest.find("SIGHUP: reloaded"), std::string::npos) << "the reload is logged: " << rest;
}

}  // namespace
}  // namespace shadowtiles
