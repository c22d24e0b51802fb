// VerifiedBlobs (a served blob's passed check stands for blob_recheck_ms) on its own, and in a real
// server whose store file is damaged under it while it serves: the damage is refused as soon as the
// standing check runs out, and at once with blob_recheck_ms = 0.
#include <algorithm>
#include <chrono>
#include <fstream>
#include <iterator>
#include <thread>

#include <gtest/gtest.h>

#include "server/verified_blobs.hpp"
#include "tests/server_test_support.hpp"

namespace shadowtiles {
namespace {

using namespace server_testing;
using namespace std::chrono_literals;
using server::VerifiedBlobs;

store::BlobHeader some_header() {
  const std::vector<uint8_t> payload(64, 7);
  auto header = store::check_blob(store::encode_blob(store::Method::raw, payload));
  EXPECT_TRUE(header.ok());
  return *header;
}

TEST(VerifiedBlobs, RecallsOnlyTheSameBuildKeyAddressAndSize) {
  VerifiedBlobs verified(10s, 100);
  auto build = std::make_shared<int>(1);
  const std::vector<uint8_t> bytes(100, 1), elsewhere(100, 1);
  const std::vector<uint8_t> key{1, 2, 3}, other_key{1, 2, 4};
  const store::BlobHeader header = some_header();
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, key, bytes)) << "nothing checked yet";
  verified.remember(build, store::Database::tiles, key, bytes, header);
  auto recalled = verified.recall(build, store::Database::tiles, key, bytes);
  ASSERT_TRUE(recalled);
  EXPECT_EQ(recalled->checksum, header.checksum);
  EXPECT_EQ(recalled->method, header.method);
  EXPECT_FALSE(verified.recall(build, store::Database::top, key, bytes)) << "another database";
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, other_key, bytes)) << "another key";
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, key, elsewhere)) << "bytes moved";
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, key, std::span(bytes).first(99))) << "resized";
  auto next_build = std::make_shared<int>(1);
  EXPECT_FALSE(verified.recall(next_build, store::Database::tiles, key, bytes)) << "another build";
  verified.remember(next_build, store::Database::tiles, other_key, bytes, header);
  EXPECT_EQ(verified.size(), 1u) << "a new build forgets the old build's entries";
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, key, bytes));
}

TEST(VerifiedBlobs, ACheckStandsOnlyForRecheckAfter) {
  VerifiedBlobs verified(50ms, 100);
  auto build = std::make_shared<int>(1);
  const std::vector<uint8_t> bytes(100, 1), key{1};
  verified.remember(build, store::Database::tiles, key, bytes, some_header());
  ASSERT_TRUE(verified.recall(build, store::Database::tiles, key, bytes));
  std::this_thread::sleep_for(60ms);
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, key, bytes)) << "past recheck_after: check again";

  VerifiedBlobs every_time(0ms, 100);
  every_time.remember(build, store::Database::tiles, key, bytes, some_header());
  EXPECT_FALSE(every_time.recall(build, store::Database::tiles, key, bytes));
  EXPECT_EQ(every_time.size(), 0u);
}

TEST(VerifiedBlobs, AFreedBuildIsNeverTakenForANewOne) {
  VerifiedBlobs verified(10s, 100);
  const std::vector<uint8_t> bytes(100, 1), key{1};
  auto build = std::make_shared<int>(1);
  verified.remember(build, store::Database::tiles, key, bytes, some_header());
  build.reset();
  auto next = std::make_shared<int>(1);  // may reuse the freed address
  EXPECT_FALSE(verified.recall(next, store::Database::tiles, key, bytes));
}

TEST(VerifiedBlobs, AFullTableStartsOver) {
  VerifiedBlobs verified(10s, 3);
  auto build = std::make_shared<int>(1);
  const std::vector<uint8_t> bytes(100, 1);
  for (uint8_t k = 0; k < 4; ++k) verified.remember(build, store::Database::tiles, std::vector<uint8_t>{k}, bytes, some_header());
  EXPECT_EQ(verified.size(), 1u);
  EXPECT_TRUE(verified.recall(build, store::Database::tiles, std::vector<uint8_t>{3}, bytes));
  EXPECT_FALSE(verified.recall(build, store::Database::tiles, std::vector<uint8_t>{0}, bytes));
}

// A raw-only bunny store, and where its tile (1, 1)'s blob lies in data.mdb.
class DamagedWhileServedTest : public ::testing::Test {
 protected:
  void SetUp() override {
    store_ = dir_.path() / "served.store";
    auto built = run_build(bunny_config(store_, {store::Method::raw}));
    ASSERT_TRUE(built.ok()) << built.error().message;
    auto store = store::Store::open(store_, {store::Store::Mode::read_only});
    ASSERT_TRUE(store.ok());
    auto blob = (*store)->get(store::Database::tiles, store::encode_tile_key({store::Method::raw, 2, 1, 1}));
    ASSERT_TRUE(blob.ok() && blob->has_value());
    blob_ = **blob;
    store->reset();
    std::ifstream in(store_ / "data.mdb", std::ios::binary);
    const std::vector<uint8_t> file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto at = std::search(file.begin(), file.end(), blob_.begin(), blob_.end());
    ASSERT_NE(at, file.end()) << "the blob is stored whole in one run of pages";
    offset_ = size_t(at - file.begin());
  }

  // A flipped payload byte written into the file under the server's map, as a failing disk would.
  void damage_the_file() {
    std::fstream file(store_ / "data.mdb", std::ios::binary | std::ios::in | std::ios::out);
    const size_t at = offset_ + blob_.size() / 2;
    file.seekp(std::streamoff(at));
    const char flipped = char(blob_[blob_.size() / 2] ^ 0x10);
    file.write(&flipped, 1);
    ASSERT_TRUE(file.good());
  }

  // Served with blob_recheck_ms = recheck_ms: the tile goes out whole, then the file is damaged
  // under the server, and `wait` later the tile is a 500, never its bytes.
  void expect_damage_refused(unsigned recheck_ms, std::chrono::milliseconds wait) {
    server::ServerConfig config = test_config();
    config.blob_recheck_ms = recheck_ms;
    RunningServer running(config, &store_);
    auto cli = running.client();
    auto first = cli.Get("/v1/tiles/raw/2/1/1");
    ASSERT_TRUE(first);
    ASSERT_EQ(first->status, 200);
    EXPECT_EQ(first->body, std::string(blob_.begin(), blob_.end()));
    damage_the_file();
    std::this_thread::sleep_for(wait);
    auto later = cli.Get("/v1/tiles/raw/2/1/1");
    expect_json_error(later, 500, "damaged tile once its check is due");
    EXPECT_EQ(later->body.find("STB1"), std::string::npos) << "never the bytes";
    auto metrics = cli.Get("/metrics");
    ASSERT_TRUE(metrics);
    EXPECT_GE(metric(metrics->body, "shadowtiles_corrupt_blobs_total"), 1u);
  }

  TempDir dir_;
  std::filesystem::path store_;
  std::vector<uint8_t> blob_;
  size_t offset_ = 0;
};

TEST_F(DamagedWhileServedTest, DamageIsRefusedOnceTheStandingCheckRunsOut) {
  expect_damage_refused(300, 400ms);
}

TEST_F(DamagedWhileServedTest, ZeroRecheckRefusesDamageAtOnce) { expect_damage_refused(0, 0ms); }

}  // namespace
}  // namespace shadowtiles
