// The blob routes end to end over HTTP on the shared bunny store (tests/bunny_server_fixture.hpp):
// tiles are the stored blobs with ETags, 304 and build-pinned URLs, sent from the store's map or
// copied past max_pinned_sends; the skip list is the stored top tree; the build record is the stored
// meta; rendered tiles are PNGs with ETags; the texel route gives each method's decoded value.
#include <gtest/gtest.h>

#include "tests/bunny_server_fixture.hpp"
#include "tests/server_test_support.hpp"

namespace shadowtiles {
namespace {

using namespace server_testing;
using ServerTest = BunnyServerTest;

// Past max_pinned_sends a blob body is copied into the response instead of sent from the map: the
// same bytes and headers. A second server with the limit at 0 (every body copied) serves a copy of
// the store (LMDB allows one environment per file per process).
TEST_F(ServerTest, CopiedTileSendsAreTheSameAsPinnedOnes) {
  const std::filesystem::path copy = dir_->path() / "copied_sends.store";
  std::filesystem::copy(store_, copy, std::filesystem::copy_options::recursive);
  server::ServerConfig config = test_config();
  config.max_pinned_sends = 0;
  RunningServer copying(config, &copy);
  auto pinned_client = server_->client();
  auto copied_client = copying.client();
  const TileLayout& layout = reference_->layout();
  size_t compared = 0;
  for (store::Method method : reference_->meta().methods) {
    for (uint32_t y = 0; y < layout.tiles_per_side(); ++y) {
      for (uint32_t x = 0; x < layout.tiles_per_side(); ++x) {
        const std::string url = std::string("/v1/tiles/") + store::method_name(method) + "/2/" + std::to_string(x) +
                                "/" + std::to_string(y);
        auto pinned = pinned_client.Get(url);
        auto copied = copied_client.Get(url);
        ASSERT_TRUE(pinned && copied) << url;
        ASSERT_EQ(copied->status, pinned->status) << url;
        if (pinned->status != 200) continue;
        auto stored = reference_->local_store()->get(store::Database::tiles, store::encode_tile_key({method, 2, x, y}));
        ASSERT_TRUE(stored.ok() && stored->has_value()) << url;
        EXPECT_EQ(copied->body, std::string((*stored)->begin(), (*stored)->end())) << url;
        EXPECT_EQ(copied->body, pinned->body) << url;
        EXPECT_EQ(copied->get_header_value("ETag"), pinned->get_header_value("ETag")) << url;
        EXPECT_EQ(copied->get_header_value("Content-Length"), pinned->get_header_value("Content-Length")) << url;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 10u) << "the bunny store has tiles to compare";
  // The skip list goes the same way.
  auto skip_pinned = pinned_client.Get("/v1/skiplist?method=mh");
  auto skip_copied = copied_client.Get("/v1/skiplist?method=mh");
  ASSERT_TRUE(skip_pinned && skip_copied);
  ASSERT_EQ(skip_pinned->status, 200);
  EXPECT_EQ(skip_copied->status, 200);
  EXPECT_FALSE(skip_copied->body.empty());
  EXPECT_EQ(skip_copied->body, skip_pinned->body);
}

TEST_F(ServerTest, TilesAreTheStoredBlobsWithEtagsAnd304) {
  auto cli = server_->client();
  const TileLayout& layout = reference_->layout();
  size_t served = 0, empty = 0;
  for (store::Method method : reference_->meta().methods) {
    for (uint32_t y = 0; y < layout.tiles_per_side(); ++y) {
      for (uint32_t x = 0; x < layout.tiles_per_side(); ++x) {
        std::string url = std::string("/v1/tiles/") + store::method_name(method) + "/2/" + std::to_string(x) + "/" +
                          std::to_string(y);
        auto res = cli.Get(url);
        ASSERT_TRUE(res);
        auto stored = reference_->local_store()->get(store::Database::tiles, store::encode_tile_key({method, 2, x, y}));
        ASSERT_TRUE(stored.ok());
        if (!stored->has_value()) {
          EXPECT_EQ(res->status, 204) << url;
          EXPECT_TRUE(res->body.empty());
          ++empty;
          continue;
        }
        ASSERT_EQ(res->status, 200) << url;
        ++served;
        EXPECT_EQ(res->body, std::string((*stored)->begin(), (*stored)->end())) << "bytes unchanged: " << url;
        auto header = store::check_blob(**stored);
        ASSERT_TRUE(header.ok());
        std::string etag = strong_etag(header->checksum);
        EXPECT_EQ(res->get_header_value("ETag"), etag);
        EXPECT_EQ(res->get_header_value("Cache-Control"), "public, no-cache") << "unversioned URLs revalidate";
        EXPECT_EQ(res->get_header_value("Content-Type"), "application/octet-stream");
        // Under the build id the same bytes are immutable; another build id is not served.
        const std::string versioned = "/v1/builds/" + reference_->meta().config_hash + url.substr(3);
        auto pinned = cli.Get(versioned);
        ASSERT_TRUE(pinned);
        ASSERT_EQ(pinned->status, 200) << versioned;
        EXPECT_EQ(pinned->body, res->body);
        EXPECT_EQ(pinned->get_header_value("ETag"), etag);
        EXPECT_EQ(pinned->get_header_value("Cache-Control"), "public, max-age=86400, immutable");
        expect_json_error(cli.Get("/v1/builds/0123456789abcdef" + url.substr(3)), 404, "another build id");

        auto again = cli.Get(url, {{"If-None-Match", etag}});
        ASSERT_TRUE(again);
        EXPECT_EQ(again->status, 304);
        EXPECT_TRUE(again->body.empty());
        EXPECT_EQ(again->get_header_value("ETag"), etag);
        auto listed = cli.Get(url, {{"If-None-Match", "\"0000000000000000\", W/" + etag}});
        ASSERT_TRUE(listed);
        EXPECT_EQ(listed->status, 304);
        auto stale = cli.Get(url, {{"If-None-Match", "\"0000000000000000\""}});
        ASSERT_TRUE(stale);
        EXPECT_EQ(stale->status, 200);

        auto head = cli.Head(url);
        ASSERT_TRUE(head);
        EXPECT_EQ(head->status, 200);
        EXPECT_TRUE(head->body.empty());
        EXPECT_EQ(head->get_header_value("ETag"), etag);
        EXPECT_EQ(head->get_header_value("Content-Length"), std::to_string((*stored)->size()));
      }
    }
  }
  EXPECT_GT(served, 0u);
  EXPECT_GT(empty, 0u) << "the bunny leaves some tiles empty";
  EXPECT_TRUE(server::if_none_match_matches("*", "\"ab\""));
  EXPECT_FALSE(server::if_none_match_matches("", "\"ab\""));
  EXPECT_FALSE(server::if_none_match_matches("ab", "\"ab\""));
}

// The skip list of a hierarchical method is its stored top tree, bytes unchanged; flat methods
// have none.
TEST_F(ServerTest, SkipListIsTheStoredTopTree) {
  auto cli = server_->client();
  auto res = cli.Get("/v1/skiplist");  // the default method, raw: flat
  expect_json_error(res, 404, "skiplist raw");
  EXPECT_NE(res->body.find("no skip list stored for method"), std::string::npos);
  for (const char* name : {"mh", "mmh"}) {
    auto method = *store::parse_method(name);
    auto stored = reference_->local_store()->get(store::Database::top, store::as_bytes(top_tree_key(method)));
    ASSERT_TRUE(stored.ok() && stored->has_value()) << name;
    auto served = cli.Get(std::string("/v1/skiplist?method=") + name);
    ASSERT_TRUE(served);
    ASSERT_EQ(served->status, 200) << name;
    EXPECT_EQ(served->body, std::string((*stored)->begin(), (*stored)->end())) << name;
    auto pinned = cli.Get("/v1/builds/" + reference_->meta().config_hash + "/skiplist?method=" + name);
    ASSERT_TRUE(pinned);
    EXPECT_EQ(pinned->status, 200);
    EXPECT_EQ(pinned->body, served->body);
  }
  expect_json_error(cli.Get("/v1/skiplist?method=bogus"), 400, "skiplist bogus");
  expect_json_error(cli.Get("/v1/skiplist?method=dagmh"), 404, "skiplist absent method");
}

// The build record a streaming client starts from: the meta JSON as stored, ETag = build id.
TEST_F(ServerTest, BuildRecordIsTheStoredMeta) {
  auto cli = server_->client();
  auto res = cli.Get("/v1/build");
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200);
  auto stored = reference_->source().meta_text();
  ASSERT_TRUE(stored.ok());
  EXPECT_EQ(res->body, *stored);
  const std::string etag = "\"" + reference_->meta().config_hash + "\"";
  EXPECT_EQ(res->get_header_value("ETag"), etag);
  auto again = cli.Get("/v1/build", {{"If-None-Match", etag}});
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 304);
}

TEST_F(ServerTest, RenderedTilesArePngsFromPreviewsThenTilesWithEtags) {
  auto cli = server_->client();
  const std::string png_magic("\x89PNG\r\n\x1a\n", 8);
  std::map<std::string, std::string> bodies;
  for (std::string layer : {"value", "depth", "coverage", "bytes", "diff&against=raw"}) {
    auto res = cli.Get("/v1/render/mh/0/0/0.png?layer=" + layer);
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200) << layer << ": " << res->body;
    EXPECT_EQ(res->get_header_value("Content-Type"), "image/png");
    EXPECT_EQ(res->body.substr(0, 8), png_magic) << layer;
    // Zoom 0 of a 512^2 map in 128^2 tiles is exactly the previews' resolution: no tile decoded.
    EXPECT_EQ(res->get_header_value("X-Shadowtiles-Source"), "previews") << layer;
    EXPECT_EQ(res->get_header_value("Cache-Control"), "public, no-cache");
    bodies[layer] = res->body;
    // Revalidation without rendering.
    httplib::Headers h = {{"If-None-Match", res->get_header_value("ETag")}};
    auto again = cli.Get("/v1/render/mh/0/0/0.png?layer=" + layer, h);
    ASSERT_TRUE(again);
    EXPECT_EQ(again->status, 304) << layer;
  }
  EXPECT_NE(bodies["value"], bodies["coverage"]);
  EXPECT_NE(bodies["value"], bodies["depth"]);
  auto raw = cli.Get("/v1/render/raw/0/0/0.png");
  ASSERT_TRUE(raw && raw->status == 200);
  EXPECT_NE(raw->get_header_value("ETag"), cli.Get("/v1/render/mh/0/0/0.png")->get_header_value("ETag"));
  // Finer zooms decode tiles; the finest magnifies.
  for (std::string url : {"/v1/render/mh/1/1/1.png", "/v1/render/mh/4/7/7.png?layer=diff&against=raw"}) {
    auto res = cli.Get(url);
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200) << url << ": " << res->body;
    EXPECT_EQ(res->get_header_value("X-Shadowtiles-Source"), "tiles") << url;
  }
  // Under the build id the tile is immutable.
  auto id = json::parse(cli.Get("/v1/meta")->body)["shadow"]["build_id"].get<std::string>();
  auto versioned = cli.Get("/v1/builds/" + id + "/render/mh/0/0/0.png?layer=depth");
  ASSERT_TRUE(versioned && versioned->status == 200);
  EXPECT_NE(versioned->get_header_value("Cache-Control").find("immutable"), std::string::npos);
  auto legend = cli.Get("/v1/render/legend?layer=value");
  ASSERT_TRUE(legend && legend->status == 200);
  auto lg = json::parse(legend->body);
  EXPECT_LT(lg["min"].get<double>(), lg["max"].get<double>());
  EXPECT_GE(lg["stops"].size(), 2u);
}

TEST_F(ServerTest, TexelRouteGivesEachMethodsDecodedValueAndTileBytes) {
  auto cli = server_->client();
  int hits = 0;
  for (uint32_t u : {10u, 200u, 255u, 300u, 511u})
    for (uint32_t v : {0u, 128u, 256u, 400u}) {
      auto res = cli.Get("/v1/texel?u=" + std::to_string(u) + "&v=" + std::to_string(v));
      ASSERT_TRUE(res);
      ASSERT_EQ(res->status, 200) << res->body;
      auto body = json::parse(res->body);
      EXPECT_EQ(body["tile"]["x"], u / 128);
      EXPECT_EQ(body["tile"]["y"], v / 128);
      ASSERT_EQ(body["methods"].size(), 3u);
      for (const auto& m : body["methods"]) {
        auto method = *store::parse_method(m["method"].get<std::string>());
        auto expected = reference_->texel_value(method, u, v);
        ASSERT_TRUE(expected.ok());
        if (*expected < 1.0f) {
          EXPECT_EQ(m["value"].get<float>(), *expected);
          ++hits;
        } else {
          EXPECT_TRUE(m["miss"].get<bool>());
        }
      }
    }
  EXPECT_GT(hits, 0);
}

}  // namespace
}  // namespace shadowtiles
