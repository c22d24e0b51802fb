// ShadowMap queries over real stores: tiling never changes an answer (point and PCF across tile
// borders), PCF 1x1 equals the point query, PCF equals a naive per-texel count, bad queries are
// errors, the tile cache stays within its byte budget.
#include <gtest/gtest.h>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "client/shadow_map.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

class ShadowMapTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    scene_file_ = testing::shared_scene("fzk_haus/fzk_haus.obj");
    for (uint32_t tile : {512u, 64u}) {
      BuildConfig config;
      config.scene_path = scene_file_;
      config.store_path = dir_->path() / ("tile" + std::to_string(tile));
      config.resolution = 512;
      config.tile_size = tile;
      config.load.up = UpAxis::y;
      config.light_direction = *light_direction_from_sun(120, 35, UpAxis::y);
      ASSERT_TRUE(run_build(config).ok());
    }
    LoadOptions load;
    load.up = UpAxis::y;
    auto scene = load_scene(scene_file_, load);
    ASSERT_TRUE(scene.ok());
    receivers_ = new std::vector<Receiver>(sample_receivers(*scene, 3000, 9));
  }
  static void TearDownTestSuite() {
    delete receivers_;
    delete dir_;
  }
  static testing::TempDir* dir_;
  static std::filesystem::path scene_file_;
  static std::vector<Receiver>* receivers_;
};
testing::TempDir* ShadowMapTest::dir_ = nullptr;
std::filesystem::path ShadowMapTest::scene_file_;
std::vector<Receiver>* ShadowMapTest::receivers_ = nullptr;

TEST_F(ShadowMapTest, OneTileAndManyTilesAnswerIdentically) {
  auto one = ShadowMap::open(dir_->path() / "tile512");
  auto many = ShadowMap::open(dir_->path() / "tile64");
  ASSERT_TRUE(one.ok() && many.ok());
  EXPECT_EQ((*many)->layout().tiles_per_side(), 8u);
  int differences = 0, crossing = 0;
  double max_value_difference = 0;
  for (const Receiver& r : *receivers_) {
    auto a = (*one)->query(r.position, store::Method::raw);
    auto b = (*many)->query(r.position, store::Method::raw);
    ASSERT_TRUE(a.ok() && b.ok());
    differences += a->lit != b->lit;
    max_value_difference = std::max(max_value_difference, std::fabs(double(a->value) - double(b->value)));
    for (unsigned k : {3u, 5u, 9u}) {
      auto pa = (*one)->query_pcf(r.position, store::Method::raw, k);
      auto pb = (*many)->query_pcf(r.position, store::Method::raw, k);
      ASSERT_TRUE(pa.ok() && pb.ok());
      differences += *pa != *pb;
    }
    uint32_t u = uint32_t(a->light.u) % 64, v = uint32_t(a->light.v) % 64;
    crossing += u < 4 || v < 4 || u > 59 || v > 59;
  }
  EXPECT_EQ(differences, 0);
  // Values are bit-identical: hit depths are re-evaluated from each triangle's global plane, so the
  // tile-local float coordinates of each tile's BVH leave no rounding trace.
  EXPECT_EQ(max_value_difference, 0.0);
  std::printf("[ figures  ] max value difference one tile vs 64 tiles: %.3g\n", max_value_difference);
  EXPECT_GT(crossing, 50) << "enough kernels cross tile borders for the test to mean something";
}

TEST_F(ShadowMapTest, PcfOneByOneIsThePointQueryAndKernelsCountTexels) {
  auto map = ShadowMap::open(dir_->path() / "tile64");
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  int checked = 0;
  for (size_t i = 0; i < receivers_->size(); i += 10) {
    const Vec3& p = (*receivers_)[i].position;
    auto point = m.query(p, store::Method::raw);
    auto pcf1 = m.query_pcf(p, store::Method::raw, 1);
    ASSERT_TRUE(point.ok() && pcf1.ok());
    EXPECT_EQ(*pcf1, point->lit ? 1.0 : 0.0);
    // Naive 5x5 count from texel values.
    auto pcf5 = m.query_pcf(p, store::Method::raw, 5);
    ASSERT_TRUE(pcf5.ok());
    int lit = 0;
    int64_t cu = int64_t(point->light.u), cv = int64_t(point->light.v);
    double threshold = point->light.depth - m.frame().depth_from_world(m.meta().default_bias);
    for (int64_t v = cv - 2; v <= cv + 2; ++v)
      for (int64_t u = cu - 2; u <= cu + 2; ++u) {
        if (u < 0 || v < 0 || u >= 512 || v >= 512) { ++lit; continue; }
        auto value = m.texel_value(store::Method::raw, uint32_t(u), uint32_t(v));
        ASSERT_TRUE(value.ok());
        lit += threshold <= double(*value);
      }
    EXPECT_EQ(*pcf5, lit / 25.0);
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST_F(ShadowMapTest, BadQueriesAreErrors) {
  auto map = ShadowMap::open(dir_->path() / "tile64");
  ASSERT_TRUE(map.ok());
  Vec3 p = (*receivers_)[0].position;
  EXPECT_FALSE((*map)->query({NAN, 0, 0}, store::Method::raw).ok());
  EXPECT_FALSE((*map)->query(p, store::Method::raw, -1.0).ok());
  EXPECT_FALSE((*map)->query(p, store::Method::mh).ok()) << "method not in the store";
  EXPECT_FALSE((*map)->query(p, store::Method::raw, {}, 10).ok()) << "512^2 has levels 0..9";
  EXPECT_TRUE((*map)->query(p, store::Method::raw, {}, 9).ok());
  for (unsigned k : {0u, 2u, 65u}) EXPECT_FALSE((*map)->query_pcf(p, store::Method::raw, k).ok()) << k;
  auto far = (*map)->query({1e6, 1e6, 1e6}, store::Method::raw);
  ASSERT_TRUE(far.ok());
  EXPECT_TRUE(far->outside_map);
  EXPECT_TRUE(far->lit);
}

TEST_F(ShadowMapTest, CacheStaysWithinItsBudget) {
  ShadowMap::Options options;
  options.cache_bytes = 3 * 64 * 64 * sizeof(float);  // three decoded raw tiles
  auto map = ShadowMap::open(dir_->path() / "tile64", options);
  ASSERT_TRUE(map.ok());
  for (const Receiver& r : *receivers_) ASSERT_TRUE((*map)->query(r.position, store::Method::raw).ok());
  CacheStats stats = (*map)->cache_stats();
  EXPECT_LE(stats.bytes, options.cache_bytes);
  EXPECT_GT(stats.misses, 3u) << "evictions forced refetches";
  EXPECT_GT(stats.hits, 0u);
}

}  // namespace
}  // namespace shadowtiles
