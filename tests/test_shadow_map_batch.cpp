// ShadowMap::query_batch on a real store with every method: each batch answer equals the
// single-point answer (query / query_pcf) exactly, for every method, PCF kernels 1..63, points on
// tile borders and off the map, coarse levels, shuffled orders, 1 or 2 threads or a caller's pool;
// bad batches are errors, and so is a batch that meets a corrupt tile in the middle of its walks.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <thread>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "client/shadow_map.hpp"
#include "codec/morton.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/store_damage.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

class ShadowMapBatchTest : public testing::BuiltStoreSuite<ShadowMapBatchTest> {
 protected:
  static void SetUpTestSuite() {
    ASSERT_NO_FATAL_FAILURE(build_fzk_haus_store(512, 1500, 3));
    auto map = ShadowMap::open(store());
    ASSERT_TRUE(map.ok());
    const ShadowMap& m = **map;
    // Texels on and beside every tile border (kernels there cross into the neighbours), on the
    // stored surface and just above it, and points off the map.
    std::mt19937 rng(11);
    const uint32_t T = m.layout().tile_size(), R = m.layout().resolution();
    for (int i = 0; i < 1500; ++i) {
      uint32_t u = uint32_t(rng() % R), v = uint32_t(rng() % R);
      const int offset = int(rng() % 7) - 3;
      if (i % 2) u = std::clamp<int64_t>(int64_t(u / T) * T + offset, 0, R - 1);
      else v = std::clamp<int64_t>(int64_t(v / T) * T + offset, 0, R - 1);
      auto value = m.texel_value(store::Method::raw, u, v);
      ASSERT_TRUE(value.ok());
      const double depth = std::isfinite(*value) ? double(*value) - (i % 3) * 1e-4 : 0.5;
      points_->push_back(m.frame().to_world({u + 0.5, v + 0.5, depth}));
    }
    points_->push_back(m.frame().to_world({-3.0, 10.0, 0.5}));
    points_->push_back(m.frame().to_world({R + 0.5, R + 2.0, 0.2}));
    points_->push_back(m.frame().to_world({0.0, 0.0, 0.999}));
    points_->push_back(m.frame().to_world({R - 0.01, R - 0.01, 0.1}));
  }
};

// Single-point answers as the batch reports them.
std::vector<float> single_answers(const ShadowMap& map, store::Method method, std::span<const Vec3> points,
                                  unsigned kernel, std::optional<unsigned> level, std::vector<uint32_t>* outside) {
  std::vector<float> lit;
  for (size_t i = 0; i < points.size(); ++i) {
    ShadowAnswer answer;
    if (kernel == 1) {
      auto a = map.query(points[i], method, {}, level);
      EXPECT_TRUE(a.ok());
      answer = *a;
      lit.push_back(a->lit ? 1.0f : 0.0f);
    } else {
      auto f = map.query_pcf(points[i], method, kernel, {}, level, &answer);
      EXPECT_TRUE(f.ok());
      lit.push_back(float(*f));
    }
    if (answer.outside_map) outside->push_back(uint32_t(i));
  }
  return lit;
}

TEST_F(ShadowMapBatchTest, BatchEqualsSinglePointForEveryMethodAndKernel) {
  auto map = ShadowMap::open(store());
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  size_t checked = 0, shadowed = 0, partial = 0;
  for (store::Method method : m.meta().methods) {
    for (unsigned kernel : {1u, 3u, 5u, 7u, 9u, 15u, 63u}) {
      std::vector<uint32_t> outside;
      const std::vector<float> expected = single_answers(m, method, *points_, kernel, {}, &outside);
      for (unsigned threads : {1u, 2u}) {
        ShadowMap::BatchOptions options;
        options.kernel = kernel;
        options.threads = threads;
        ShadowMap::BatchAnswers answers;
        ASSERT_TRUE(m.query_batch(*points_, method, options, answers).ok());
        ASSERT_EQ(answers.lit.size(), expected.size());
        for (size_t i = 0; i < expected.size(); ++i)
          ASSERT_EQ(answers.lit[i], expected[i]) << store::method_name(method) << " k" << kernel << " point " << i;
        EXPECT_EQ(answers.outside, outside);
      }
      checked += expected.size();
      shadowed += std::count(expected.begin(), expected.end(), 0.0f);
      for (float f : expected) partial += f > 0 && f < 1;
      EXPECT_EQ(outside.size(), 2u) << "the two points placed off the map";
    }
  }
  EXPECT_GT(shadowed, checked / 20) << "the points see both light and shadow";
  EXPECT_GT(partial, 1000u) << "PCF kernels straddle shadow edges";
}

TEST_F(ShadowMapBatchTest, CoarseLevelsShuffledOrdersAndPoolsAgree) {
  auto map = ShadowMap::open(store());
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  std::vector<Vec3> shuffled = *points_;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(4));
  for (store::Method method : m.meta().methods) {
    for (std::optional<unsigned> level : {std::optional<unsigned>{1}, std::optional<unsigned>{5}, std::optional<unsigned>{}}) {
      for (unsigned kernel : {1u, 3u}) {
        std::vector<uint32_t> outside;
        const std::vector<float> expected = single_answers(m, method, shuffled, kernel, level, &outside);
        ShadowMap::BatchOptions options;
        options.kernel = kernel;
        options.level = level;
        // A caller's pool: three uneven parts on two threads.
        options.parallel_for = [](size_t count, const std::function<void(size_t, size_t)>& fn) {
          std::thread other([&] { fn(count / 3, count); });
          fn(0, count / 3);
          other.join();
        };
        ShadowMap::BatchAnswers answers;
        ASSERT_TRUE(m.query_batch(shuffled, method, options, answers).ok());
        EXPECT_EQ(answers.lit, expected) << store::method_name(method) << " level " << level.value_or(99) << " k" << kernel;
        EXPECT_EQ(answers.outside, outside);
      }
    }
  }
}

// query_batch sorts a bucket along the curve only when its points are dense; the fixture's points are
// sparse (about one per bucket), so here every texel of a region around a tile corner, on the surface
// and just above or below it, makes dense buckets: the sorted shared-path walks (points, and PCF
// kernels sharing descents to their common ancestors) must agree too.
TEST_F(ShadowMapBatchTest, DenseBatchesAgree) {
  auto map = ShadowMap::open(store());
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  const uint32_t C = m.layout().resolution() / 2;  // a tile corner at the scene's centre
  std::vector<Vec3> dense;
  for (uint32_t v = C - 40; v < C + 40; ++v)
    for (uint32_t u = C - 40; u < C + 40; ++u) {
      auto value = m.texel_value(store::Method::raw, u, v);
      ASSERT_TRUE(value.ok());
      const double depth = std::isfinite(*value) ? double(*value) + ((u + v) % 3 - 1.0) * 0.02 : 0.5;
      dense.push_back(m.frame().to_world({u + 0.3 + 0.4 * ((u * 7 + v) % 2), v + 0.5, depth}));
    }
  std::shuffle(dense.begin(), dense.end(), std::mt19937(9));
  size_t shadowed = 0;
  for (store::Method method : m.meta().methods) {
    for (unsigned kernel : {1u, 3u, 7u}) {
      std::vector<uint32_t> outside;
      const std::vector<float> expected = single_answers(m, method, dense, kernel, {}, &outside);
      ShadowMap::BatchOptions options;
      options.kernel = kernel;
      options.threads = 2;
      ShadowMap::BatchAnswers answers;
      ASSERT_TRUE(m.query_batch(dense, method, options, answers).ok());
      EXPECT_EQ(answers.lit, expected) << store::method_name(method) << " k" << kernel;
      EXPECT_TRUE(answers.outside.empty());
      shadowed += std::count(expected.begin(), expected.end(), 0.0f);
    }
  }
  EXPECT_GT(shadowed, dense.size() / 2) << "the dense points see shadow too";
}

TEST_F(ShadowMapBatchTest, BadBatchesAreErrors) {
  auto map = ShadowMap::open(store());
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  ShadowMap::BatchAnswers answers;
  std::vector<Vec3> points(points_->begin(), points_->begin() + 100);
  EXPECT_TRUE(m.query_batch({}, store::Method::mh, {}, answers).ok());
  EXPECT_TRUE(answers.lit.empty());
  // A failed batch leaves no answers: not the last batch's, nor a part of its own.
  ASSERT_TRUE(m.query_batch(points, store::Method::mh, {}, answers).ok());
  ASSERT_EQ(answers.lit.size(), points.size());
  points[57] = {0, NAN, 0};
  auto bad = m.query_batch(points, store::Method::mh, {}, answers);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::invalid_input);
  EXPECT_TRUE(answers.lit.empty());
  EXPECT_TRUE(answers.outside.empty());
  // Infinite coordinates too, on every axis and both signs (the batch checks finiteness only for
  // points its transform puts off the map, which every such point is).
  for (int axis = 0; axis < 3; ++axis)
    for (double infinite : {double(INFINITY), -double(INFINITY)}) {
      points[57] = (*points_)[0];
      points[57][axis] = infinite;
      auto error = m.query_batch(points, store::Method::mh, {}, answers);
      ASSERT_FALSE(error.ok()) << axis << " " << infinite;
      EXPECT_EQ(error.error().code, ErrorCode::invalid_input);
    }
  points[57] = (*points_)[0];
  ShadowMap::BatchOptions options;
  options.kernel = 4;
  ASSERT_TRUE(m.query_batch(points, store::Method::mh, {}, answers).ok());
  EXPECT_EQ(m.query_batch(points, store::Method::mh, options, answers).error().code, ErrorCode::invalid_input);
  EXPECT_TRUE(answers.lit.empty());
  options.kernel = 1;
  options.bias = -1.0;
  EXPECT_EQ(m.query_batch(points, store::Method::mh, options, answers).error().code, ErrorCode::invalid_input);
  options.bias = {};
  options.level = 10;
  EXPECT_EQ(m.query_batch(points, store::Method::mh, options, answers).error().code, ErrorCode::invalid_input);
  options.level = {};
  EXPECT_TRUE(m.query_batch(points, store::Method::mh, options, answers).ok());
  EXPECT_EQ(answers.lit.size(), points.size());
}

// A tile whose stored blob fails its checksum, met by the walks after other tiles were answered and
// the points off the map were listed: the batch is corrupt_data, with neither answers nor the
// outside list left behind, and no answer of the damaged method is served from that tile later.
// MH goes through the sorted pipeline, raw through the chunked one (client/shadow_batch.cpp).
TEST_F(ShadowMapBatchTest, ACorruptTileMidBatchIsAnErrorWithNoAnswers) {
  for (store::Method damaged_method : {store::Method::mh, store::Method::raw}) {
    SCOPED_TRACE(store::method_name(damaged_method));
    const store::Method other = damaged_method == store::Method::mh ? store::Method::raw : store::Method::mh;
    testing::TempDir dir;
    const auto damaged = dir.path() / "damaged.store";
    std::filesystem::copy(store(), damaged, std::filesystem::copy_options::recursive);
    TileCoord target{};
    {
      auto clean = ShadowMap::open(store());
      ASSERT_TRUE(clean.ok());
      const ShadowMap& m = **clean;
      // Of the stored tiles holding points, the last in Morton order, the order the MH walks take:
      // the points in the tiles before it are answered first.
      std::optional<TileCoord> tile;
      size_t stored_tiles = 0;
      for (const Vec3& p : *points_) {
        auto t = m.tile_of(p);
        if (!t || (tile && morton_encode(t->x, t->y) <= morton_encode(tile->x, tile->y))) continue;
        auto decoded = m.tile(damaged_method, *t);
        ASSERT_TRUE(decoded.ok());
        if (*decoded) tile = t, ++stored_tiles;
      }
      ASSERT_TRUE(tile.has_value());
      ASSERT_GT(stored_tiles, 2u) << "stored tiles met in rising Morton order: at least two come before the target";
      target = *tile;
      testing::flip_a_bit_in_stored_tile(damaged, {damaged_method, m.layout().tile_level(), target.x, target.y});
    }
    auto map = ShadowMap::open(damaged);
    ASSERT_TRUE(map.ok());
    const ShadowMap& m = **map;
    for (unsigned kernel : {1u, 3u})
      for (unsigned threads : {1u, 2u}) {  // one worker: the tiles before the damaged one are answered first
        ShadowMap::BatchAnswers answers;
        ShadowMap::BatchOptions options;
        options.kernel = kernel;
        options.threads = threads;
        // The same answers object held a whole batch of another method a moment ago.
        ASSERT_TRUE(m.query_batch(*points_, other, options, answers).ok());
        ASSERT_FALSE(answers.outside.empty()) << "the points include some off the map";
        auto batch = m.query_batch(*points_, damaged_method, options, answers);
        ASSERT_FALSE(batch.ok()) << "kernel " << kernel;
        EXPECT_EQ(batch.error().code, ErrorCode::corrupt_data) << batch.error().message;
        EXPECT_TRUE(answers.lit.empty()) << "kernel " << kernel << ", threads " << threads;
        EXPECT_TRUE(answers.outside.empty()) << "kernel " << kernel << ", threads " << threads;
      }
    // A later single query in the damaged tile is the same error, not an answer; another method's
    // tiles at the same place still answer.
    auto in_target = std::find_if(points_->begin(), points_->end(), [&](const Vec3& p) {
      auto t = m.tile_of(p);
      return t && t->x == target.x && t->y == target.y;
    });
    ASSERT_NE(in_target, points_->end());
    auto single = m.query(*in_target, damaged_method);
    ASSERT_FALSE(single.ok());
    EXPECT_EQ(single.error().code, ErrorCode::corrupt_data);
    EXPECT_TRUE(m.query(*in_target, store::Method::dagmh).ok());
    ShadowMap::BatchAnswers answers;
    EXPECT_TRUE(m.query_batch(*points_, store::Method::dagmh, {}, answers).ok());
    EXPECT_EQ(answers.lit.size(), points_->size());
  }
}

}  // namespace
}  // namespace shadowtiles
