// End to end over HTTP: a real store (bunny, 512^2 in 128^2 tiles, raw + mh + mmh) served by the
// real server on an ephemeral loopback port, queried with httplib::Client. Answers are compared
// with a ShadowMap opened on a copy of the store (one process must not open one LMDB directory
// twice). Covers meta, health, metrics, point/PCF/batch answers, query options, CORS, every bad
// input and 8 concurrent clients. The blob routes (tiles, skip list, build record, renders, texels)
// are in test_server_blobs.cpp, a damaged store and the connection limit in
// test_server_damaged_store.cpp, the serve process itself in test_serve_process.cpp.
#include <gtest/gtest.h>

#include "tests/bunny_server_fixture.hpp"
#include "tests/server_test_support.hpp"

namespace shadowtiles {
namespace {

using namespace server_testing;

// The shared bunny store and server (tests/bunny_server_fixture.hpp).
using ServerTest = BunnyServerTest;

TEST_F(ServerTest, MetaIsTileJsonWithTheShadowFrame) {
  auto cli = server_->client();
  auto res = cli.Get("/v1/meta");
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200);
  auto meta = json::parse(res->body);
  EXPECT_EQ(meta["tilejson"], "3.0.0");
  EXPECT_EQ(meta["scheme"], "xyz");
  EXPECT_EQ(meta["tiles"][0], "/v1/builds/" + reference_->meta().config_hash + "/tiles/{method}/{z}/{x}/{y}");
  EXPECT_EQ(meta["minzoom"], 2);
  EXPECT_EQ(meta["maxzoom"], 2);
  EXPECT_EQ(meta["bounds"], json({0.0, 0.0, 512.0, 512.0}));
  const json& shadow = meta["shadow"];
  EXPECT_EQ(shadow["resolution"], 512);
  EXPECT_EQ(shadow["tile_size"], 128);
  EXPECT_EQ(shadow["levels"], 10);
  EXPECT_EQ(shadow["methods"], json({"raw", "mh", "mmh"}));
  EXPECT_EQ(shadow["format_version"], kStoreFormatVersion);
  EXPECT_EQ(shadow["build_id"], reference_->meta().config_hash);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(shadow["light"]["direction"][i].get<double>(), reference_->frame().direction()[i]);
  EXPECT_TRUE(shadow["build_stats"].is_object());
  EXPECT_EQ(meta["name"], "stanford-bunny.obj") << "no server paths in the document";
}

TEST_F(ServerTest, HealthAndMetrics) {
  auto cli = server_->client();
  auto health = cli.Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  auto before = cli.Get("/metrics");
  ASSERT_TRUE(before);
  EXPECT_EQ(before->status, 200);
  EXPECT_NE(before->get_header_value("Content-Type").find("text/plain"), std::string::npos);
  ASSERT_TRUE(cli.Get(shadow_url((*points_)[0])));
  ASSERT_TRUE(cli.Post("/v1/shadow", json{{"points", points_json({(*points_)[1], (*points_)[2]})}}.dump(),
                       "application/json"));
  ASSERT_TRUE(cli.Get("/v1/tiles/raw/2/9/9"));
  auto after = cli.Get("/metrics");
  ASSERT_TRUE(after);
  EXPECT_EQ(metric(after->body, "shadowtiles_points_answered_total"),
            metric(before->body, "shadowtiles_points_answered_total") + 3);
  EXPECT_GT(metric(after->body, "shadowtiles_tile_cache_misses_total"), 0u);
  EXPECT_GT(metric(after->body, "shadowtiles_tile_cache_locked_lookups_total"),
            metric(before->body, "shadowtiles_tile_cache_locked_lookups_total"));
  EXPECT_GT(metric(after->body, "shadowtiles_tile_cache_fetched_bytes_total"),
            metric(before->body, "shadowtiles_tile_cache_fetched_bytes_total"));
  EXPECT_GT(metric(after->body, "shadowtiles_tile_cache_bytes"), 0u);
  EXPECT_NE(after->body.find("shadowtiles_http_requests_total{route=\"/v1/tiles\",method=\"GET\",status=\"404\"}"),
            std::string::npos);
  EXPECT_NE(after->body.find("shadowtiles_http_request_duration_seconds_bucket{route=\"/v1/shadow\",le=\"+Inf\"}"),
            std::string::npos);
}

// 10,000 surface points (+2 outside the map), every method: single GETs equal ShadowMap::query,
// JSON PCF batches equal query_pcf, binary batches equal JSON batches and the decoder.
TEST_F(ServerTest, AnswersEqualTheDecoderForEveryMethod) {
  auto cli = server_->client();
  const std::vector<Vec3>& points = *points_;
  for (store::Method method : reference_->meta().methods) {
    const std::string name = store::method_name(method);
    size_t mismatches = 0, shadowed = 0;
    for (const Vec3& p : points) {
      auto res = cli.Get(shadow_url(p, "&method=" + name));
      ASSERT_TRUE(res);
      ASSERT_EQ(res->status, 200) << res->body;
      auto got = json::parse(res->body);
      auto want = reference_->query(p, method);
      ASSERT_TRUE(want.ok());
      shadowed += !want->lit;
      mismatches += got["lit"].get<double>() != (want->lit ? 1.0 : 0.0) || got["shadowed"] != !want->lit ||
                    got["outside_map"] != want->outside_map;
      if (!want->outside_map) {
        mismatches += got["u"].get<double>() != want->light.u || got["v"].get<double>() != want->light.v ||
                      got["depth"].get<double>() != want->light.depth;
      }
    }
    EXPECT_EQ(mismatches, 0u) << name;
    EXPECT_GT(shadowed, points.size() / 20) << name << ": the sample must hold shadowed points";

    // PCF 3x3 as one JSON batch.
    auto res = cli.Post("/v1/shadow", json{{"points", points_json(points)}, {"pcf", 3}, {"method", name}}.dump(),
                        "application/json");
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200) << res->body;
    auto batch = json::parse(res->body);
    ASSERT_EQ(batch["lit"].size(), points.size());
    EXPECT_EQ(batch["outside_map"], json({points.size() - 2, points.size() - 1}));
    size_t pcf_mismatches = 0, fractional = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      auto want = reference_->query_pcf(points[i], method, 3);
      ASSERT_TRUE(want.ok());
      pcf_mismatches += batch["lit"][i].get<double>() != double(float(*want));
      fractional += *want > 0 && *want < 1;
    }
    EXPECT_EQ(pcf_mismatches, 0u) << name;
    EXPECT_GT(fractional, 0u) << name << ": some kernels straddle a shadow edge";

    // A single PCF GET.
    auto one = cli.Get(shadow_url(points[3], "&pcf=5&method=" + name));
    ASSERT_TRUE(one);
    EXPECT_EQ(json::parse(one->body)["lit"].get<double>(), *reference_->query_pcf(points[3], method, 5));

    // Binary batch of float32 points = JSON batch of the same (float-rounded) points = decoder.
    std::vector<Vec3> rounded;
    for (const Vec3& p : points) rounded.push_back({double(float(p[0])), double(float(p[1])), double(float(p[2]))});
    auto binary = cli.Post(("/v1/shadow?method=" + name).c_str(), encode_points(rounded), "application/octet-stream");
    ASSERT_TRUE(binary);
    ASSERT_EQ(binary->status, 200) << binary->body;
    EXPECT_EQ(binary->get_header_value("X-Shadow-Outside-Map"), "2");
    auto lit = decode_floats(binary->body);
    ASSERT_EQ(lit.size(), points.size());
    // An empty batch is a valid empty answer (fuzz_http regression binary-batch-of-no-point: the
    // answer's memcpy got a null buffer, undefined behaviour caught by UBSan).
    auto none = cli.Post(("/v1/shadow?pcf=3&method=" + name).c_str(), std::string(), "application/octet-stream");
    ASSERT_TRUE(none);
    EXPECT_EQ(none->status, 200) << none->body;
    EXPECT_TRUE(none->body.empty());
    EXPECT_EQ(none->get_header_value("X-Shadow-Outside-Map"), "0");
    auto as_json = cli.Post("/v1/shadow", json{{"points", points_json(rounded)}, {"method", name}}.dump(),
                            "application/json");
    ASSERT_TRUE(as_json);
    auto json_lit = json::parse(as_json->body)["lit"];
    size_t binary_mismatches = 0;
    for (size_t i = 0; i < rounded.size(); ++i) {
      auto want = reference_->query(rounded[i], method);
      ASSERT_TRUE(want.ok());
      binary_mismatches += lit[i] != (want->lit ? 1.0f : 0.0f) || json_lit[i].get<double>() != double(lit[i]);
    }
    EXPECT_EQ(binary_mismatches, 0u) << name;
  }
}

TEST_F(ServerTest, QueryOptionsLevelAndBias) {
  auto cli = server_->client();
  const Vec3 p = (*points_)[5];
  auto res = cli.Get(shadow_url(p, "&method=mh&level=4&bias=0.001"));
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  auto want = reference_->query(p, store::Method::mh, 0.001, 4u);
  ASSERT_TRUE(want.ok());
  EXPECT_EQ(json::parse(res->body)["lit"].get<double>(), want->lit ? 1.0 : 0.0);
  auto outside = cli.Get(shadow_url({1e6, 0, 0}));
  ASSERT_TRUE(outside);
  auto body = json::parse(outside->body);
  EXPECT_EQ(body["lit"].get<double>(), 1.0);
  EXPECT_EQ(body["outside_map"], true);
}

TEST_F(ServerTest, Cors) {
  auto cli = server_->client();
  auto allowed = cli.Get("/v1/meta", {{"Origin", kAllowedOrigin}});
  ASSERT_TRUE(allowed);
  EXPECT_EQ(allowed->get_header_value("Access-Control-Allow-Origin"), kAllowedOrigin);
  EXPECT_EQ(allowed->get_header_value("Vary"), "Origin");
  auto denied = cli.Get("/v1/meta", {{"Origin", "https://evil.example"}});
  ASSERT_TRUE(denied);
  EXPECT_EQ(denied->status, 200);
  EXPECT_FALSE(denied->has_header("Access-Control-Allow-Origin"));
  EXPECT_EQ(denied->get_header_value("Vary"), "Origin");
  auto error = cli.Get("/v1/shadow?x=1", {{"Origin", kAllowedOrigin}});
  ASSERT_TRUE(error);
  EXPECT_EQ(error->status, 400);
  EXPECT_EQ(error->get_header_value("Access-Control-Allow-Origin"), kAllowedOrigin) << "errors readable by the page";

  auto preflight = cli.Options("/v1/shadow", {{"Origin", kAllowedOrigin}, {"Access-Control-Request-Method", "POST"},
                                              {"Access-Control-Request-Headers", "content-type"}});
  ASSERT_TRUE(preflight);
  EXPECT_EQ(preflight->status, 204);
  EXPECT_EQ(preflight->get_header_value("Access-Control-Allow-Origin"), kAllowedOrigin);
  EXPECT_NE(preflight->get_header_value("Access-Control-Allow-Methods").find("POST"), std::string::npos);
  EXPECT_NE(preflight->get_header_value("Access-Control-Allow-Headers").find("Content-Type"), std::string::npos);
  auto refused = cli.Options("/v1/shadow", {{"Origin", "https://evil.example"}, {"Access-Control-Request-Method", "POST"}});
  expect_json_error(refused, 403, "preflight from another origin");
  EXPECT_FALSE(refused->has_header("Access-Control-Allow-Origin"));
}

TEST_F(ServerTest, EveryBadInputGetsA4xxAndTheServerKeepsAnswering) {
  auto cli = server_->client();
  const std::vector<std::pair<std::string, int>> gets = {
      {"/v1/shadow", 400},
      {"/v1/shadow?x=1&y=2", 400},
      {"/v1/shadow?x=abc&y=0&z=0", 400},
      {"/v1/shadow?x=&y=0&z=0", 400},
      {"/v1/shadow?x=1x&y=0&z=0", 400},
      {"/v1/shadow?x=nan&y=0&z=0", 400},
      {"/v1/shadow?x=inf&y=0&z=0", 400},
      {"/v1/shadow?x=-inf&y=0&z=0", 400},
      {"/v1/shadow?x=1e999&y=0&z=0", 400},
      {"/v1/shadow?x=0&y=0&z=0&x=1", 400},
      {"/v1/shadow?x=0&y=0&z=0&pcf=0", 400},
      {"/v1/shadow?x=0&y=0&z=0&pcf=2", 400},
      {"/v1/shadow?x=0&y=0&z=0&pcf=17", 400},
      {"/v1/shadow?x=0&y=0&z=0&pcf=99999999999999999999999", 400},
      {"/v1/shadow?x=0&y=0&z=0&pcf=-3", 400},
      {"/v1/shadow?x=0&y=0&z=0&pcf=3.0", 400},
      {"/v1/shadow?x=0&y=0&z=0&method=bogus", 400},
      {"/v1/shadow?x=0&y=0&z=0&method=dagmh", 400},
      {"/v1/shadow?x=0&y=0&z=0&method=", 400},
      {"/v1/shadow?x=0&y=0&z=0&level=10", 400},
      {"/v1/shadow?x=0&y=0&z=0&level=-1", 400},
      {"/v1/shadow?x=0&y=0&z=0&level=256", 400},
      {"/v1/shadow?x=0&y=0&z=0&bias=-1", 400},
      {"/v1/shadow?x=0&y=0&z=0&bias=nan", 400},
      {"/v1/shadow?x=0&y=0&z=0&pfc=3", 400},
      {"/v1/tiles/raw/2/x/1", 400},
      {"/v1/tiles/raw/2/1/1.png", 400},
      {"/v1/tiles/raw/2/-1/0", 400},
      {"/v1/tiles/raw/2/99999999999/0", 400},
      {"/v1/tiles/bogus/2/0/0", 400},
      {"/v1/tiles/dagmh/2/0/0", 404},
      {"/v1/tiles/raw/3/0/0", 404},
      {"/v1/tiles/raw/0/0/0", 404},
      {"/v1/tiles/raw/2/4/0", 404},
      {"/v1/tiles/raw/2/0/4", 404},
      {"/v1/tiles/raw/2/0", 404},
      {"/v1/nope", 404},
      {std::string(7000, 'a').insert(0, 1, '/'), 404},
      {"/v1/tiles/raw/2/" + std::string(7000, '1') + "/0", 400},
      {"/v1/shadow?x=" + std::string(7000, '9') + "&y=0&z=0", 400},
      // The inspector's rendered tiles (512^2 map: zooms 0..4) and texel route.
      {"/v1/render/raw/5/0/0.png", 404},
      {"/v1/render/raw/99999999999/0/0.png", 400},
      {"/v1/render/raw/4294967295/0/0.png", 404},
      {"/v1/render/raw/1/2/0.png", 404},
      {"/v1/render/raw/1/0/2.png", 404},
      {"/v1/render/raw/0/1/0.png", 404},
      {"/v1/render/raw/-1/0/0.png", 400},
      {"/v1/render/raw/0/0/x.png", 400},
      {"/v1/render/raw/0/0/0.5.png", 400},
      {"/v1/render/bogus/0/0/0.png", 400},
      {"/v1/render/dagmh/0/0/0.png", 404},
      {"/v1/render/raw/0/0/0.png?layer=heat", 400},
      {"/v1/render/raw/0/0/0.png?layer=", 400},
      {"/v1/render/raw/0/0/0.png?layer=diff", 400},
      {"/v1/render/raw/0/0/0.png?layer=diff&against=dagmh", 404},
      {"/v1/render/raw/0/0/0.png?layer=diff&against=bogus", 400},
      {"/v1/render/raw/0/0/0.png?against=mh", 400},
      {"/v1/render/raw/0/0/0.png?layer=value&layer=depth", 400},
      {"/v1/render/raw/0/0/0.png?foo=1", 400},
      {"/v1/builds/nope/render/raw/0/0/0.png", 404},
      {"/v1/render/legend?layer=x", 400},
      {"/v1/texel?u=512&v=0", 404},
      {"/v1/texel?u=a&v=0", 400},
      {"/v1/texel?u=1", 400},
      {"/v1/texel?u=1&v=1&u=2", 400},
      {"/inspector/leaflet/../../etc/passwd", 404},
      {"/inspector/nope.js", 404},
  };
  for (const auto& [url, status] : gets) expect_json_error(cli.Get(url), status, "GET " + url.substr(0, 80));
  {
    auto res = cli.Get(std::string(20000, 'a').insert(0, 1, '/'));
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 414);
  }

  const std::string good_point = json{{"points", {{0, 0.1, 0}}}}.dump();
  struct Post {
    std::string path, body, type;
    int status;
  };
  std::string deep(100000, '[');
  const std::vector<Post> posts = {
      {"/v1/shadow", good_point, "text/plain", 415},
      {"/v1/shadow", good_point, "application/x-www-form-urlencoded", 415},
      {"/v1/shadow", "{", "application/json", 400},
      {"/v1/shadow", "", "application/json", 400},
      {"/v1/shadow", "[]", "application/json", 400},
      {"/v1/shadow", "{}", "application/json", 400},
      {"/v1/shadow", "{\"points\": 3}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0]]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0, 0]]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, \"a\", 0]]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 1e999, 0]]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, NaN, 0]]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[[0, 0, 0]]]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [], \"points\": []}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"pcf\": 4}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"pcf\": \"3\"}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"pcf\": 99}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"method\": \"bogus\"}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"method\": \"dagmh\"}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"level\": 99}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"bias\": -1}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"extra\": 1}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]], \"pcf\": [3]}", "application/json", 400},
      {"/v1/shadow", "{\"points\": [[0, 0, 0]]} trailing", "application/json", 400},
      {"/v1/shadow?pcf=3", good_point, "application/json", 400},
      {"/v1/shadow", deep, "application/json", 400},
      {"/v1/shadow", std::string(13, '\0'), "application/octet-stream", 400},
      {"/v1/shadow", std::string(11, '\0'), "application/octet-stream", 400},
      {"/v1/shadow", encode_points({{0, NAN, 0}}), "application/octet-stream", 400},
      {"/v1/shadow", encode_points({{0, 0, INFINITY}}), "application/octet-stream", 400},
      {"/v1/shadow?pcf=4", encode_points({{0, 0, 0}}), "application/octet-stream", 400},
      {"/v1/shadow?method=bogus", encode_points({{0, 0, 0}}), "application/octet-stream", 400},
      {"/v1/shadow?nope=1", encode_points({{0, 0, 0}}), "application/octet-stream", 400},
      {"/v1/shadow", std::string(3 << 20, ' '), "application/json", 413},
      {"/v1/shadow", std::string(12 * 20001, '\0'), "application/octet-stream", 413},
      {"/v1/shadow", json{{"points", points_json(std::vector<Vec3>(20001, Vec3{0, 0, 0}))}}.dump(), "application/json", 413},
      {"/v1/meta", "{}", "application/json", 404},
  };
  for (const Post& p : posts)
    expect_json_error(cli.Post(p.path.c_str(), p.body, p.type.c_str()), p.status,
                      "POST " + p.path + " " + p.type + " " + p.body.substr(0, 40));
  auto empty_binary = cli.Post("/v1/shadow", "", "application/octet-stream");
  ASSERT_TRUE(empty_binary);
  EXPECT_EQ(empty_binary->status, 200) << "zero points is a valid (empty) batch";
  EXPECT_TRUE(empty_binary->body.empty());

  expect_json_error(cli.Delete("/v1/meta"), 405, "DELETE");
  expect_json_error(cli.Put("/v1/meta", "x", "text/plain"), 405, "PUT");

  // A raw request line the HTTP layer cannot parse, then the server still answers.
  {
    httplib::Client raw("127.0.0.1", server_->port());
    auto garbage = raw.Get("/v1/shadow?x=%zz&y=0&z=0");
    ASSERT_TRUE(garbage);
    EXPECT_EQ(garbage->status, 400);
  }
  auto health = cli.Get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  auto answer = cli.Get(shadow_url((*points_)[0]));
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->status, 200);
}

// 8 client threads x 1,000 mixed requests against the 2-thread server: no errors, every answer
// equals the decoder's.
TEST_F(ServerTest, EightConcurrentClients) {
  constexpr int kThreads = 8, kRequests = 1000;
  const std::vector<Vec3>& points = *points_;
  const auto& methods = reference_->meta().methods;
  std::atomic<int> failures{0};
  std::vector<std::string> messages(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      auto cli = server_->client();
      std::mt19937 random(t);
      auto fail = [&](const std::string& why) {
        if (failures.fetch_add(1) < 5) messages[t] = why;
      };
      for (int i = 0; i < kRequests; ++i) {
        const Vec3& p = points[random() % points.size()];
        store::Method method = methods[random() % methods.size()];
        const std::string name = store::method_name(method);
        switch (i % 5) {
          case 0: {
            auto res = cli.Get(shadow_url(p, "&method=" + name));
            auto want = reference_->query(p, method);
            if (!res || res->status != 200 || json::parse(res->body)["lit"].get<double>() != (want->lit ? 1.0 : 0.0))
              fail("point " + name);
            break;
          }
          case 1: {
            auto res = cli.Get(shadow_url(p, "&pcf=3&method=" + name));
            auto want = reference_->query_pcf(p, method, 3);
            if (!res || res->status != 200 || json::parse(res->body)["lit"].get<double>() != *want) fail("pcf " + name);
            break;
          }
          case 2: {
            uint32_t x = random() % 4, y = random() % 4;
            auto res = cli.Get("/v1/tiles/" + name + "/2/" + std::to_string(x) + "/" + std::to_string(y));
            auto stored = reference_->local_store()->get(store::Database::tiles, store::encode_tile_key({method, 2, x, y}));
            bool ok = res && (stored->has_value()
                                  ? res->status == 200 && res->body == std::string((*stored)->begin(), (*stored)->end())
                                  : res->status == 204);
            if (!ok) fail("tile " + name);
            break;
          }
          case 3: {
            std::vector<Vec3> some;
            for (int k = 0; k < 50; ++k) some.push_back(points[random() % points.size()]);
            auto res = cli.Post("/v1/shadow", json{{"points", points_json(some)}, {"method", name}}.dump(),
                                "application/json");
            if (!res || res->status != 200) {
              fail("json batch");
              break;
            }
            auto lit = json::parse(res->body)["lit"];
            for (size_t k = 0; k < some.size(); ++k)
              if (lit[k].get<double>() != (reference_->query(some[k], method)->lit ? 1.0 : 0.0)) fail("json batch value");
            break;
          }
          default: {
            std::vector<Vec3> some;
            for (int k = 0; k < 50; ++k) {
              const Vec3& q = points[random() % points.size()];
              some.push_back({double(float(q[0])), double(float(q[1])), double(float(q[2]))});
            }
            auto res = cli.Post(("/v1/shadow?pcf=3&method=" + name).c_str(), encode_points(some),
                                "application/octet-stream");
            if (!res || res->status != 200 || res->body.size() != some.size() * 4) {
              fail("binary batch");
              break;
            }
            auto lit = decode_floats(res->body);
            for (size_t k = 0; k < some.size(); ++k)
              if (lit[k] != float(*reference_->query_pcf(some[k], method, 3))) fail("binary batch value");
          }
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  std::string all;
  for (const std::string& m : messages)
    if (!m.empty()) all += m + "; ";
  EXPECT_EQ(failures.load(), 0) << all;
}

}  // namespace
}  // namespace shadowtiles
