// SST through the whole pipeline on real scenes (real Embree, real LMDB store): every texel of every
// tile decodes inside its recomputed [lower, upper] interval (exhaustive, via verify_store), PCF
// through the tile's quadtrees equals per-texel counting, point queries agree with the lossless MH.
// The 4096^2 run over every shared scene is tests/test_sst_long.cpp (ctest label `long`).
#include <gtest/gtest.h>

#include <cstdio>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "builder/store_verifier.hpp"
#include "client/shadow_map.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"
#include "tests/verified_build.hpp"

namespace shadowtiles {
namespace {

using SceneCase = testing::SharedSceneCase;

constexpr SceneCase kTerrain{"terragen/RealisticTerrain.ply", UpAxis::z, true};
constexpr SceneCase kHouse{"fzk_haus/fzk_haus.obj", UpAxis::y, false};

BuildConfig config_for(const SceneCase& scene, const std::filesystem::path& out, uint32_t resolution, uint32_t tile,
                       std::vector<store::Method> methods) {
  return testing::shared_scene_config(scene, out, resolution, tile, std::move(methods));
}

void expect_lossless(const SceneCase& scene, uint32_t resolution, uint32_t tile, std::vector<store::Method> methods) {
  testing::TempDir dir;
  auto verified = testing::build_and_verify_every_texel(config_for(scene, dir.path() / "s", resolution, tile, methods),
                                                        methods);
  ASSERT_TRUE(verified.has_value());
  const auto& bytes = verified->stats["bytes_by_method"];
  std::printf("[ figures  ] %s %u^2 tiles %u: bytes", scene.file, resolution, tile);
  for (store::Method m : methods)
    std::printf(" %s %llu", store::method_name(m), (unsigned long long)bytes[store::method_name(m)].get<uint64_t>());
  std::printf("\n");
}

TEST(SstScenes, TerrainHeightfieldIsLossless) {
  expect_lossless(kTerrain, 1024, 256, {store::Method::raw, store::Method::mh, store::Method::sst});
}
TEST(SstScenes, OpenBuildingIsLosslessWithSstAlone) { expect_lossless(kHouse, 1024, 256, {store::Method::sst}); }

TEST(SstScenes, PcfAndPointQueriesThroughTheStore) {
  testing::TempDir dir;
  const SceneCase scene{"bunny/stanford-bunny.obj", UpAxis::y, false};
  // The bunny as an open scan (--no-nearly-closed): intervals are points where hit.
  BuildConfig config = config_for(scene, dir.path() / "s", 1024, 256, {store::Method::mh, store::Method::sst});
  config.close_nearly_closed = false;
  ASSERT_TRUE(run_build(config).ok());
  auto loaded = load_scene(testing::shared_scene(scene.file), LoadOptions{{}, UpAxis::y});
  ASSERT_TRUE(loaded.ok());
  const std::vector<Receiver> receivers = sample_receivers(*loaded, 1500, 5);
  auto map = ShadowMap::open(dir.path() / "s");
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  int crossing = 0;
  for (const Receiver& r : receivers) {
    // Open mesh: intervals are points where hit, so both lossless methods give the same answers.
    auto sst = m.query(r.position, store::Method::sst);
    auto mh = m.query(r.position, store::Method::mh);
    ASSERT_TRUE(sst.ok() && mh.ok());
    EXPECT_EQ(sst->lit, mh->lit);
    for (unsigned k : {3u, 7u}) {
      ShadowAnswer answer;
      auto fast = m.query_pcf(r.position, store::Method::sst, k, {}, {}, &answer);
      ASSERT_TRUE(fast.ok());
      const float threshold = float(answer.light.depth - m.frame().depth_from_world(m.meta().default_bias));
      const int64_t cu = int64_t(answer.light.u), cv = int64_t(answer.light.v), half = k / 2;
      uint64_t lit = 0;
      for (int64_t v = cv - half; v <= cv + half; ++v)
        for (int64_t u = cu - half; u <= cu + half; ++u) {
          if (u < 0 || v < 0 || u >= 1024 || v >= 1024) { ++lit; continue; }
          auto value = m.texel_value(store::Method::sst, uint32_t(u), uint32_t(v));
          ASSERT_TRUE(value.ok());
          lit += threshold <= *value;
        }
      ASSERT_EQ(*fast, double(lit) / double(k * k)) << "k=" << k;
      if (k == 7 && (cu % 128 < 3 || cu % 128 > 124 || cv % 128 < 3 || cv % 128 > 124)) ++crossing;
    }
  }
  EXPECT_GT(crossing, 10) << "kernels across block and tile borders are exercised";
}

}  // namespace
}  // namespace shadowtiles
