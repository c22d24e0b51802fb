// The server on a damaged store (a real store whose raw tile (1, 1) fails its checksum): a corrupt
// blob is never served and /healthz waits for a good store; and the connection limit: a client beyond
// max_connections gets a quick 503 instead of queueing.
#include <gtest/gtest.h>

#include "tests/server_test_support.hpp"

namespace shadowtiles {
namespace {

using namespace server_testing;

// A store (raw + mh) whose raw tile (1, 1) fails its checksum; its mh skip list is intact.
class DamagedStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    store_ = dir_.path() / "damaged.store";
    auto built = run_build(bunny_config(store_, {store::Method::raw, store::Method::mh}));
    ASSERT_TRUE(built.ok()) << built.error().message;
    auto store = store::Store::open(store_, {store::Store::Mode::read_write});
    ASSERT_TRUE(store.ok());
    auto key = store::encode_tile_key({store::Method::raw, 2, 1, 1});
    auto blob = (*store)->get(store::Database::tiles, key);
    ASSERT_TRUE(blob.ok() && blob->has_value());
    std::vector<uint8_t> bytes = **blob;
    bytes[bytes.size() / 2] ^= 0x10;
    auto top = (*store)->get(store::Database::top, store::as_bytes(top_tree_key(store::Method::mh)));
    ASSERT_TRUE(top.ok() && top->has_value());
    skiplist_ = **top;
    std::vector<store::Store::Put> puts{{store::Database::tiles, {key.begin(), key.end()}, bytes}};
    ASSERT_TRUE((*store)->write(puts).ok());
    store->reset();
    // A world point whose texel lies in tile (1, 1); the map is closed again before any server
    // opens the directory (one LMDB environment per directory and process).
    auto map = ShadowMap::open(store_);
    ASSERT_TRUE(map.ok());
    in_corrupt_tile_ = (*map)->frame().to_world(LightSpacePoint{192, 192, 0.5});
  }
  TempDir dir_;
  Vec3 in_corrupt_tile_{};
  std::filesystem::path store_;
  std::vector<uint8_t> skiplist_;
};

TEST_F(DamagedStoreTest, CorruptBlobIsNeverServedAndHealthWaitsForTheStore) {
  RunningServer running(test_config(), nullptr);
  auto cli = running.client();
  expect_json_error(cli.Get("/healthz"), 503, "healthz before the store is attached");
  expect_json_error(cli.Get("/v1/meta"), 503, "meta before the store is attached");
  expect_json_error(cli.Get("/v1/shadow?x=0&y=0&z=0"), 503, "shadow before the store is attached");
  ASSERT_TRUE(running.server().attach_store(store_).ok());
  auto health = cli.Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);

  auto corrupt = cli.Get("/v1/tiles/raw/2/1/1");
  expect_json_error(corrupt, 500, "corrupt tile");
  EXPECT_EQ(json::parse(corrupt->body)["code"], "corrupt_data");
  EXPECT_FALSE(corrupt->has_header("ETag"));
  EXPECT_EQ(corrupt->body.find("STB1"), std::string::npos) << "never the bytes";
  auto head = cli.Head("/v1/tiles/raw/2/1/1");
  ASSERT_TRUE(head);
  EXPECT_EQ(head->status, 500);

  // A point whose texel lies in the corrupt tile: an error, never an answer.
  const Vec3& world = in_corrupt_tile_;
  char url[200];
  std::snprintf(url, sizeof url, "/v1/shadow?x=%.17g&y=%.17g&z=%.17g", world[0], world[1], world[2]);
  expect_json_error(cli.Get(url), 500, "point in the corrupt tile");
  expect_json_error(cli.Post("/v1/shadow", encode_points({world}), "application/octet-stream"), 500,
                    "batch touching the corrupt tile");

  auto good = cli.Get("/v1/tiles/raw/2/1/2");
  ASSERT_TRUE(good);
  EXPECT_EQ(good->status, 200) << "other tiles still served";

  auto skiplist = cli.Get("/v1/skiplist?method=mh");
  ASSERT_TRUE(skiplist);
  ASSERT_EQ(skiplist->status, 200);
  EXPECT_EQ(skiplist->body, std::string(skiplist_.begin(), skiplist_.end()));
  std::string etag = strong_etag(store::check_blob(skiplist_)->checksum);
  EXPECT_EQ(skiplist->get_header_value("ETag"), etag);
  auto cached = cli.Get("/v1/skiplist?method=mh", {{"If-None-Match", etag}});
  ASSERT_TRUE(cached);
  EXPECT_EQ(cached->status, 304);

  auto metrics = cli.Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_GE(metric(metrics->body, "shadowtiles_corrupt_blobs_total"), 2u);
}

// max_connections = 1: while one keep-alive client holds the only slot, a new connection gets a
// quick 503 instead of queueing; once the slot frees, new connections are served again.
TEST_F(DamagedStoreTest, ConnectionsBeyondTheLimitGet503) {
  auto config = test_config();
  config.threads = 1;
  config.max_connections = 1;
  config.keep_alive_timeout_s = 5;
  RunningServer running(config, &store_);
  EXPECT_FALSE(running.server().attach_store(store_).ok()) << "a second attach is refused";
  auto status_of_new_connection = [&] {
    httplib::Client c("127.0.0.1", running.port());
    auto res = c.Get("/healthz");
    return res ? res->status : -1;
  };
  auto holder = std::make_unique<httplib::Client>("127.0.0.1", running.port());
  holder->set_keep_alive(true);
  int held = -1;
  // The probe connection of RunningServer may still hold the slot for a moment (seconds on a loaded
  // machine: the worker must be scheduled to see the probe's close).
  for (int i = 0; i < 1000 && held != 200; ++i) {
    auto res = holder->Get("/healthz");
    held = res ? res->status : -1;
    if (held != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(held, 200);
  httplib::Client other("127.0.0.1", running.port());
  expect_json_error(other.Get("/v1/meta"), 503, "connection over the limit");
  holder.reset();  // frees the slot
  int status = -1;
  for (int i = 0; i < 1000 && status != 200; ++i) {
    status = status_of_new_connection();
    if (status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(status, 200);
}

}  // namespace
}  // namespace shadowtiles
