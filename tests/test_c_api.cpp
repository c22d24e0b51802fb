// The C API (capi/shadowtiles.h) over a real store: its answers equal ShadowMap's (point, PCF,
// batch, tile values), batches from several threads on one map equal the serial answers, errors
// come back as codes with per-thread messages and write no output, and surface points lie on the
// lower bound the light sees.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "capi/shadowtiles.h"
#include "client/shadow_map.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

class CApiTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    BuildConfig config = testing::fzk_haus_config(dir_->path() / "store", 256, {store::Method::mh, store::Method::raw, store::Method::dagmh});
    ASSERT_TRUE(run_build(config).ok());
    LoadOptions load;
    load.up = UpAxis::y;
    auto scene = load_scene(config.scene_path, load);
    ASSERT_TRUE(scene.ok());
    points_ = new std::vector<double>;
    for (const Receiver& r : sample_receivers(*scene, 20000, 3))
      points_->insert(points_->end(), r.position.begin(), r.position.end());
  }
  static void TearDownTestSuite() {
    delete points_;
    delete dir_;
  }
  void SetUp() override {
    ASSERT_EQ(shadowtiles_open(store_path().c_str(), 0, &map_), SHADOWTILES_OK) << shadowtiles_last_error();
    auto opened = ShadowMap::open(store_path());
    ASSERT_TRUE(opened.ok());
    reference_ = std::move(*opened);
  }
  void TearDown() override { shadowtiles_close(map_); }
  static std::string store_path() { return (dir_->path() / "store").string(); }
  static size_t count() { return points_->size() / 3; }
  static Vec3 point(size_t i) { return {(*points_)[3 * i], (*points_)[3 * i + 1], (*points_)[3 * i + 2]}; }

  static testing::TempDir* dir_;
  static std::vector<double>* points_;
  shadowtiles_map* map_ = nullptr;
  std::unique_ptr<ShadowMap> reference_;
};
testing::TempDir* CApiTest::dir_ = nullptr;
std::vector<double>* CApiTest::points_ = nullptr;

TEST_F(CApiTest, PointPcfAndBatchEqualShadowMap) {
  std::vector<uint8_t> lit(count()), outside(count());
  std::vector<float> values(count());
  for (const char* method : {"mh", "dagmh", "raw"}) {
    const store::Method m = *store::parse_method(method);
    ASSERT_EQ(shadowtiles_query_batch(map_, method, points_->data(), count(), -1, 2, lit.data(), values.data(),
                                      outside.data()),
              SHADOWTILES_OK)
        << shadowtiles_last_error();
    size_t shadowed = 0;
    for (size_t i = 0; i < count(); ++i) {
      auto expected = reference_->query(point(i), m);
      ASSERT_TRUE(expected.ok());
      ASSERT_EQ(bool(lit[i]), expected->lit) << method << " point " << i;
      ASSERT_EQ(values[i], expected->value) << method << " point " << i;
      ASSERT_EQ(bool(outside[i]), expected->outside_map);
      shadowed += !lit[i];
    }
    // Lit flags only: the sorted batch path (ShadowMap::query_batch) answers the same.
    std::vector<uint8_t> fast_lit(count(), 7), fast_outside(count(), 7);
    ASSERT_EQ(shadowtiles_query_batch(map_, method, points_->data(), count(), -1, 2, fast_lit.data(), nullptr,
                                      fast_outside.data()),
              SHADOWTILES_OK)
        << shadowtiles_last_error();
    EXPECT_EQ(fast_lit, lit) << method;
    EXPECT_EQ(fast_outside, outside) << method;
    EXPECT_GT(shadowed, count() / 50) << "the receivers must include shadowed ones";
    EXPECT_LT(shadowed, count() - count() / 50);

    shadowtiles_answer answer;
    for (size_t i = 0; i < count(); i += 997) {
      ASSERT_EQ(shadowtiles_query(map_, method, points_->data() + 3 * i, -1, &answer), SHADOWTILES_OK);
      auto expected = reference_->query(point(i), m);
      EXPECT_EQ(bool(answer.lit), expected->lit);
      EXPECT_EQ(answer.value, expected->value);
      EXPECT_EQ(answer.u, expected->light.u);
      EXPECT_EQ(answer.depth, expected->light.depth);
    }
    std::vector<double> fractions(count());
    ASSERT_EQ(shadowtiles_query_pcf_batch(map_, method, points_->data(), count(), 5, -1, 0, fractions.data()),
              SHADOWTILES_OK);
    for (size_t i = 0; i < count(); i += 101) {
      auto expected = reference_->query_pcf(point(i), m, 5);
      ASSERT_TRUE(expected.ok());
      EXPECT_EQ(fractions[i], double(float(*expected))) << "the batch answers in float";
      double single = -1;
      ASSERT_EQ(shadowtiles_query_pcf(map_, method, points_->data() + 3 * i, 5, -1, &single, nullptr), SHADOWTILES_OK);
      EXPECT_EQ(single, *expected);
    }
  }
  // NULL and "" name the build's default method (its first: mh).
  std::vector<uint8_t> by_default(count()), by_name(count());
  ASSERT_EQ(shadowtiles_query_batch(map_, nullptr, points_->data(), count(), -1, 1, by_default.data(), nullptr, nullptr),
            SHADOWTILES_OK);
  ASSERT_EQ(shadowtiles_query_batch(map_, "mh", points_->data(), count(), -1, 1, by_name.data(), nullptr, nullptr),
            SHADOWTILES_OK);
  EXPECT_EQ(by_default, by_name);
}

TEST_F(CApiTest, ConcurrentBatchesOnOneMapEqualTheSerialAnswers) {
  std::vector<uint8_t> serial(count());
  std::vector<float> serial_values(count());
  ASSERT_EQ(shadowtiles_query_batch(map_, "dagmh", points_->data(), count(), -1, 1, serial.data(),
                                    serial_values.data(), nullptr),
            SHADOWTILES_OK);
  constexpr int kThreads = 4;
  std::vector<std::vector<uint8_t>> lit(kThreads, std::vector<uint8_t>(count()));
  std::vector<std::vector<float>> values(kThreads, std::vector<float>(count()));
  std::vector<shadowtiles_status> status(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      // Each thread also fails once: its message must stay its own.
      double nan_point[3] = {NAN, 0, 0};
      shadowtiles_answer unused;
      if (shadowtiles_query(map_, t % 2 ? "mh" : "nonsense", nan_point, -1, &unused) == SHADOWTILES_OK) return;
      const std::string message = shadowtiles_last_error();
      status[t] = shadowtiles_query_batch(map_, "dagmh", points_->data(), count(), -1, 2,
                                          lit[t].data(), values[t].data(), nullptr);
      if (std::string(shadowtiles_last_error()) != message) status[t] = SHADOWTILES_INTERNAL;
    });
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_EQ(status[t], SHADOWTILES_OK) << "thread " << t;
    EXPECT_EQ(lit[t], serial) << "thread " << t;
    EXPECT_EQ(values[t], serial_values) << "thread " << t;
  }
}

TEST_F(CApiTest, ErrorsAreCodesWithMessagesAndWriteNothing) {
  shadowtiles_map* none = reinterpret_cast<shadowtiles_map*>(0x1);
  EXPECT_EQ(shadowtiles_open((dir_->path() / "missing").c_str(), 0, &none), SHADOWTILES_NOT_FOUND);
  EXPECT_NE(std::string(shadowtiles_last_error()).find("missing"), std::string::npos) << shadowtiles_last_error();
  EXPECT_EQ(none, reinterpret_cast<shadowtiles_map*>(0x1)) << "out written on failure";
  EXPECT_EQ(shadowtiles_open("http://", 0, &none), SHADOWTILES_INVALID_INPUT) << shadowtiles_last_error();
  EXPECT_EQ(shadowtiles_open(nullptr, 0, &none), SHADOWTILES_INVALID_INPUT);

  std::vector<double> points(points_->begin(), points_->begin() + 3 * 3000);
  points[3 * 2500 + 1] = INFINITY;  // one bad point: the whole batch fails, naming it
  std::vector<uint8_t> lit(3000, 7);
  EXPECT_EQ(shadowtiles_query_batch(map_, "mh", points.data(), 3000, -1, 2, lit.data(), nullptr, nullptr),
            SHADOWTILES_INVALID_INPUT);
  EXPECT_NE(std::string(shadowtiles_last_error()).find("point 2500"), std::string::npos) << shadowtiles_last_error();
  EXPECT_EQ(shadowtiles_query_batch(map_, "cpvs", points.data(), 10, -1, 1, lit.data(), nullptr, nullptr),
            SHADOWTILES_UNSUPPORTED);
  EXPECT_NE(std::string(shadowtiles_last_error()).find("cpvs"), std::string::npos);
  EXPECT_EQ(shadowtiles_query_batch(map_, "MH", points.data(), 10, -1, 1, lit.data(), nullptr, nullptr),
            SHADOWTILES_INVALID_INPUT);
  EXPECT_EQ(shadowtiles_query_batch(map_, "mh", points.data(), 10, NAN, 1, lit.data(), nullptr, nullptr),
            SHADOWTILES_INVALID_INPUT);
  EXPECT_EQ(shadowtiles_query_batch(map_, "mh", points.data(), 10, -1, 1, nullptr, nullptr, nullptr),
            SHADOWTILES_INVALID_INPUT);
  double fraction = -1;
  EXPECT_EQ(shadowtiles_query_pcf(map_, "mh", points.data(), 4, -1, &fraction, nullptr), SHADOWTILES_INVALID_INPUT);
  EXPECT_EQ(fraction, -1);
  std::vector<float> small(10);
  EXPECT_EQ(shadowtiles_tile_values(map_, "mh", 0, 0, small.data(), small.size()), SHADOWTILES_INVALID_INPUT);
  std::vector<float> tile(64 * 64);
  EXPECT_EQ(shadowtiles_tile_values(map_, "mh", 4, 0, tile.data(), tile.size()), SHADOWTILES_INVALID_INPUT);
  EXPECT_STREQ(shadowtiles_status_name(SHADOWTILES_CORRUPT_DATA), "corrupt_data");
  shadowtiles_close(nullptr);
}

TEST_F(CApiTest, MetaInfoTilesAndSurfacePoints) {
  const char* json = nullptr;
  ASSERT_EQ(shadowtiles_meta_json(map_, &json), SHADOWTILES_OK);
  EXPECT_EQ(nlohmann::json::parse(json), reference_->meta().to_json());
  shadowtiles_info info;
  ASSERT_EQ(shadowtiles_get_info(map_, &info), SHADOWTILES_OK);
  EXPECT_EQ(info.resolution, 256u);
  EXPECT_EQ(info.tile_size, 64u);
  EXPECT_EQ(info.tiles_per_side, 4u);
  EXPECT_EQ(info.levels, 9u);
  EXPECT_EQ(info.default_bias, reference_->meta().default_bias);

  std::vector<float> values(64 * 64);
  std::vector<double> xyz(3 * 64 * 64);
  std::vector<uint8_t> hit(64 * 64);
  size_t hits = 0;
  for (uint32_t y = 0; y < 4; ++y) {
    for (uint32_t x = 0; x < 4; ++x) {
      ASSERT_EQ(shadowtiles_tile_values(map_, "dagmh", x, y, values.data(), values.size()), SHADOWTILES_OK);
      auto tile = reference_->tile(store::Method::dagmh, {x, y});
      ASSERT_TRUE(tile.ok());
      for (uint32_t v = 0; v < 64; v += 7)
        for (uint32_t u = 0; u < 64; u += 5)
          EXPECT_EQ(values[v * 64 + u], *tile ? (*tile)->value(u, v) : INFINITY);

      ASSERT_EQ(shadowtiles_surface_points(map_, x, y, xyz.data(), hit.data(), hit.size()), SHADOWTILES_OK);
      for (size_t i = 0; i < hit.size(); ++i) {
        if (!hit[i]) continue;
        ++hits;
        // The point projects back onto its texel centre at the raw lower bound, and is lit.
        const Vec3 p{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
        const LightSpacePoint l = reference_->frame().to_light(p);
        EXPECT_NEAR(l.u, x * 64.0 + i % 64 + 0.5, 1e-6);
        EXPECT_NEAR(l.v, y * 64.0 + i / 64 + 0.5, 1e-6);
        auto raw = reference_->texel_value(store::Method::raw, x * 64 + uint32_t(i % 64), y * 64 + uint32_t(i / 64));
        ASSERT_TRUE(raw.ok());
        EXPECT_NEAR(l.depth, *raw, 1e-9);
        if (i % 31 == 0) {
          auto answer = reference_->query(p, store::Method::mh);
          ASSERT_TRUE(answer.ok());
          EXPECT_TRUE(answer->lit) << "the first hit of a light ray is lit";
        }
      }
    }
  }
  EXPECT_GT(hits, 256u * 256 / 10);
}

}  // namespace
}  // namespace shadowtiles
