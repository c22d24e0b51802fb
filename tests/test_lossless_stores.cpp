// MH and MMH through the whole pipeline on real scenes: every texel of every tile decodes inside its
// recomputed [lower, upper] interval (exhaustive), PCF through the hierarchy's common-ancestor path
// equals per-texel counting (kernels across tile borders too), MMH is no larger than MH, coarse
// levels come from the top tree.
#include <gtest/gtest.h>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "builder/store_verifier.hpp"
#include "client/shadow_map.hpp"
#include "store/lmdb_store.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"
#include "tests/verified_build.hpp"

namespace shadowtiles {
namespace {

// Raw beside the MH family, for the size comparisons.
const std::vector<store::Method> kMethods = {store::Method::raw, store::Method::mh, store::Method::mmh,
                                             store::Method::dagmh};

struct LosslessCase {
  testing::SharedSceneCase scene;
  // Open geometry has point intervals (entry = exit) on most hit texels: the hierarchy must store
  // a value per texel on sloped surfaces and can be larger than zstd'd raw floats.
  bool expect_smaller_than_raw = true;
};

BuildConfig config_for(const testing::SharedSceneCase& scene, const std::filesystem::path& out, uint32_t resolution,
                       uint32_t tile) {
  return testing::shared_scene_config(scene, out, resolution, tile, kMethods);
}

void expect_lossless(const LosslessCase& c, uint32_t resolution, uint32_t tile) {
  testing::TempDir dir;
  auto verified =
      testing::build_and_verify_every_texel(config_for(c.scene, dir.path() / "s", resolution, tile), kMethods);
  ASSERT_TRUE(verified.has_value());
  const auto& bytes = verified->stats["bytes_by_method"];
  EXPECT_LE(bytes["mmh"].get<uint64_t>(), bytes["mh"].get<uint64_t>()) << "merging never grows a tile";
  if (c.expect_smaller_than_raw) {
    EXPECT_LT(bytes["mh"].get<uint64_t>(), bytes["raw"].get<uint64_t>());
  }
  std::printf("[ figures  ] %s %u^2 tiles %u: bytes raw %llu mh %llu mmh %llu dagmh %llu (mmh/mh %.3f dagmh/mmh %.3f)\n",
              c.scene.file, resolution, tile, (unsigned long long)bytes["raw"].get<uint64_t>(),
              (unsigned long long)bytes["mh"].get<uint64_t>(), (unsigned long long)bytes["mmh"].get<uint64_t>(),
              (unsigned long long)bytes["dagmh"].get<uint64_t>(),
              double(bytes["mmh"].get<uint64_t>()) / double(bytes["mh"].get<uint64_t>()),
              double(bytes["dagmh"].get<uint64_t>()) / double(bytes["mmh"].get<uint64_t>()));
}

TEST(LosslessStores, NefertitiClosedMeshAt4096) {
  expect_lossless({{"nefertiti/nefertiti.obj", UpAxis::z, false}}, 4096, 1024);
}
TEST(LosslessStores, FzkHausOpenBuildingAt4096) {
  expect_lossless({{"fzk_haus/fzk_haus.obj", UpAxis::y, false}, false}, 4096, 1024);
}
TEST(LosslessStores, TerragenHeightfieldAt2048) {
  expect_lossless({{"terragen/RealisticTerrain.ply", UpAxis::z, true}}, 2048, 512);
}

class HierarchyQueries : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    const testing::SharedSceneCase scene{"bunny/stanford-bunny.obj", UpAxis::y, false};
    // The bunny as an open scan (--no-nearly-closed): upper == lower wherever it is hit.
    BuildConfig config = config_for(scene, dir_->path() / "s", 1024, 128);
    config.close_nearly_closed = false;
    ASSERT_TRUE(run_build(config).ok());
    auto loaded = load_scene(testing::shared_scene(scene.file), LoadOptions{{}, UpAxis::y});
    ASSERT_TRUE(loaded.ok());
    receivers_ = new std::vector<Receiver>(sample_receivers(*loaded, 2000, 5));
  }
  static void TearDownTestSuite() {
    delete receivers_;
    delete dir_;
  }
  static testing::TempDir* dir_;
  static std::vector<Receiver>* receivers_;
};
testing::TempDir* HierarchyQueries::dir_ = nullptr;
std::vector<Receiver>* HierarchyQueries::receivers_ = nullptr;

TEST_F(HierarchyQueries, PcfThroughTheHierarchyEqualsPerTexelCounting) {
  auto map = ShadowMap::open(dir_->path() / "s");
  ASSERT_TRUE(map.ok());
  const ShadowMap& m = **map;
  int crossing = 0;
  for (const Receiver& r : *receivers_) {
    for (store::Method method : {store::Method::mh, store::Method::mmh, store::Method::dagmh}) {
      for (unsigned k : {3u, 5u, 7u}) {
        ShadowAnswer answer;
        auto fast = m.query_pcf(r.position, method, k, {}, {}, &answer);
        ASSERT_TRUE(fast.ok());
        float threshold = float(answer.light.depth - m.frame().depth_from_world(m.meta().default_bias));
        int64_t cu = int64_t(answer.light.u), cv = int64_t(answer.light.v), half = k / 2;
        uint64_t lit = 0;
        for (int64_t v = cv - half; v <= cv + half; ++v)
          for (int64_t u = cu - half; u <= cu + half; ++u) {
            if (u < 0 || v < 0 || u >= 1024 || v >= 1024) { ++lit; continue; }
            auto value = m.texel_value(method, uint32_t(u), uint32_t(v));
            ASSERT_TRUE(value.ok());
            lit += threshold <= *value;
          }
        ASSERT_EQ(*fast, double(lit) / double(k * k)) << store::method_name(method) << " k=" << k;
        if (k == 7 && (cu % 128 < 3 || cu % 128 > 124 || cv % 128 < 3 || cv % 128 > 124)) ++crossing;
      }
    }
  }
  EXPECT_GT(crossing, 20) << "kernels across tile borders are exercised";
}

TEST_F(HierarchyQueries, LosslessMethodsAnswerPointQueriesLikeRawUpToTheBias) {
  // Raw compares with the entry depth; MH/MMH with a value inside [entry, exit - margin]. They may
  // differ only where a receiver lies beyond the entry (inside or under a closed object, in which
  // case the raw answer is the shadowed one and the lossless one may be lit only if the receiver is
  // inside the solid). On the open bunny (upper == lower everywhere it is hit) they must agree.
  auto map = ShadowMap::open(dir_->path() / "s");
  ASSERT_TRUE(map.ok());
  int differences = 0;
  for (const Receiver& r : *receivers_) {
    auto raw = (*map)->query(r.position, store::Method::raw);
    auto mh = (*map)->query(r.position, store::Method::mh);
    auto mmh = (*map)->query(r.position, store::Method::mmh);
    ASSERT_TRUE(raw.ok() && mh.ok() && mmh.ok());
    differences += raw->lit != mh->lit;
    differences += raw->lit != mmh->lit;
  }
  EXPECT_EQ(differences, 0);
}

TEST_F(HierarchyQueries, CoarseLevelsComeFromTheTopTree) {
  auto map = ShadowMap::open(dir_->path() / "s");
  ASSERT_TRUE(map.ok());
  auto store = store::Store::open(dir_->path() / "s", {});
  ASSERT_TRUE(store.ok());
  const store::Method hierarchical[] = {store::Method::mh, store::Method::mmh, store::Method::dagmh};
  for (store::Method m : hierarchical) {
    auto top = (*store)->get(store::Database::top, store::as_bytes(top_tree_key(m)));
    ASSERT_TRUE(top.ok() && top->has_value()) << "top tree stored for " << store::method_name(m);
  }
  // Every level answers; level 0 is one value for the whole map, so every receiver gets the same.
  // (Without a top tree, coarse levels fall back to each tile's root: level 0 would differ per tile.)
  for (store::Method m : hierarchical) {
    std::optional<float> level0;
    for (const Receiver& r : *receivers_) {
      for (unsigned level = 0; level < (*map)->level_count(); ++level) {
        auto answer = (*map)->query(r.position, m, {}, level);
        ASSERT_TRUE(answer.ok()) << store::method_name(m) << " level " << level;
        if (level == 0) {
          if (!level0) level0 = answer->value;
          EXPECT_EQ(answer->value, *level0) << store::method_name(m);
        }
      }
    }
  }
}

}  // namespace
}  // namespace shadowtiles
