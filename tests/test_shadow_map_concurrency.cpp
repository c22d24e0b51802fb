// ShadowMap from many threads on a real store with every method: answers from 8 concurrent threads
// (point and PCF, each thread in its own order) equal the single-thread answers exactly; 8 threads
// missing the same tiles at once fetch each tile once; a cache smaller than the working set (tiles
// evicted while other threads hold pins) still answers exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <barrier>
#include <random>
#include <thread>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "client/shadow_map.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

constexpr unsigned kThreads = 8;

class ShadowMapConcurrencyTest : public testing::BuiltStoreSuite<ShadowMapConcurrencyTest> {
 protected:
  static void SetUpTestSuite() { ASSERT_NO_FATAL_FAILURE(build_fzk_haus_store(512, 2000, 5)); }
};

// Answer of one query as a comparable number: lit (0/1) for kernel 1, the PCF fraction otherwise;
// -1 for an error.
double answer(const ShadowMap& map, store::Method method, const Vec3& p, unsigned kernel) {
  if (kernel == 1) {
    auto a = map.query(p, method);
    return a ? (a->lit ? 1.0 : 0.0) : -1.0;
  }
  auto f = map.query_pcf(p, method, kernel);
  return f ? *f : -1.0;
}

void expect_threads_match(const ShadowMap& map, const std::vector<Vec3>& points) {
  for (store::Method method : map.meta().methods) {
    for (unsigned kernel : {1u, 3u, 5u}) {
      std::vector<double> expected(points.size());
      for (size_t i = 0; i < points.size(); ++i) expected[i] = answer(map, method, points[i], kernel);
      ASSERT_EQ(std::count(expected.begin(), expected.end(), -1.0), 0);
      std::vector<std::vector<double>> got(kThreads, std::vector<double>(points.size()));
      std::vector<std::thread> pool;
      for (unsigned t = 0; t < kThreads; ++t)
        pool.emplace_back([&, t] {
          std::vector<size_t> order(points.size());
          for (size_t i = 0; i < order.size(); ++i) order[i] = i;
          if (t % 2) std::shuffle(order.begin(), order.end(), std::mt19937(t));  // odd threads: random order
          for (size_t i : order) got[t][i] = answer(map, method, points[i], kernel);
        });
      for (auto& th : pool) th.join();
      for (unsigned t = 0; t < kThreads; ++t)
        EXPECT_EQ(got[t], expected) << store::method_name(method) << " kernel " << kernel << " thread " << t;
    }
  }
}

TEST_F(ShadowMapConcurrencyTest, EightThreadsAnswerAsOne) {
  auto map = ShadowMap::open(store());
  ASSERT_TRUE(map.ok());
  expect_threads_match(**map, *points_);
}

TEST_F(ShadowMapConcurrencyTest, ConcurrentMissesFetchEachTileOnce) {
  auto map = ShadowMap::open(store());
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  const uint32_t tiles = m.layout().tiles_per_side();
  std::barrier start(kThreads);
  std::vector<std::thread> pool;
  std::atomic<int> errors{0};
  for (unsigned t = 0; t < kThreads; ++t)
    pool.emplace_back([&] {
      start.arrive_and_wait();  // all threads miss the same tiles at the same time
      for (uint32_t y = 0; y < tiles; ++y)
        for (uint32_t x = 0; x < tiles; ++x)
          if (!m.texel_value(store::Method::dagmh, x * m.layout().tile_size(), y * m.layout().tile_size()))
            ++errors;
    });
  for (auto& th : pool) th.join();
  EXPECT_EQ(errors.load(), 0);
  const CacheStats stats = m.cache_stats();
  EXPECT_EQ(stats.misses, uint64_t(tiles) * tiles) << "every tile fetched exactly once";
  EXPECT_EQ(stats.tiles, uint64_t(tiles) * tiles);
  std::printf("[ figures  ] %u threads x %u tiles: %llu fetches, %llu misses waited for another thread's fetch\n",
              kThreads, tiles * tiles, (unsigned long long)stats.misses, (unsigned long long)stats.shared_misses);
}

TEST_F(ShadowMapConcurrencyTest, EvictionUnderConcurrentLookupsStaysExact) {
  ShadowMap::Options options;
  options.cache_bytes = 4 * 64 * 64 * sizeof(float);  // a few raw tiles: constant eviction
  auto map = ShadowMap::open(store(), options);
  ASSERT_TRUE(map.ok());
  expect_threads_match(**map, std::vector<Vec3>(points_->begin(), points_->begin() + 400));
  const CacheStats stats = (*map)->cache_stats();
  EXPECT_GT(stats.evictions, 0u);
  EXPECT_LE(stats.bytes, options.cache_bytes);
}

// A thread's pins hold a slot per tile of the map (up to 128 tiles a side): once every tile of a
// 16 x 16-tile or a 64 x 64-tile map has been read, reading each again (in an order that jumps
// across the map, as random queries do) goes through no lock. (With a fixed 8 x 8 table, most of
// these went through the locked cache.)
TEST(ShadowMapPins, EveryTileOfAMapStaysPinnedAfterOnePass) {
  for (const uint32_t tile_size : {32u, 8u}) {
    testing::TempDir dir;
    const BuildConfig config = testing::shared_scene_config({"fzk_haus/fzk_haus.obj", UpAxis::y, false},
                                                            dir.path() / "store", 512, tile_size, {store::Method::dagmh});
    ASSERT_TRUE(run_build(config).ok());
    auto map = ShadowMap::open(dir.path() / "store");
    ASSERT_TRUE(map.ok());
    const ShadowMap& m = **map;
    const uint32_t tiles = m.layout().tiles_per_side();
    ASSERT_EQ(tiles, 512 / tile_size);
    std::vector<std::pair<uint32_t, uint32_t>> order;
    for (uint32_t y = 0; y < tiles; ++y)
      for (uint32_t x = 0; x < tiles; ++x) order.push_back({x, y});
    std::shuffle(order.begin(), order.end(), std::mt19937(3));
    for (const auto& [x, y] : order)
      ASSERT_TRUE(m.texel_value(store::Method::dagmh, x * tile_size + 1, y * tile_size + 2).ok());
    const uint64_t after_first = m.cache_stats().locked_lookups;
    EXPECT_GE(after_first, uint64_t(tiles) * tiles);  // each tile pinned once through the cache
    std::shuffle(order.begin(), order.end(), std::mt19937(4));
    for (const auto& [x, y] : order)
      ASSERT_TRUE(m.texel_value(store::Method::dagmh, x * tile_size + 3, y * tile_size).ok());
    EXPECT_EQ(m.cache_stats().locked_lookups, after_first) << tiles << " x " << tiles << " tiles";
    EXPECT_EQ(m.cache_stats().evictions, 0u);
  }
}

}  // namespace
}  // namespace shadowtiles
