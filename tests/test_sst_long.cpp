// Long (ctest label `long`, not run in the default CI suite): issue #7's exhaustive check. Every
// shared scene at 4096^2 (tiles of 1024^2) built with SST beside MH: every texel of the map decodes
// inside its recomputed [lower, upper] interval and answers a depth just outside it exactly.
// ~1 min per scene on 2 cores.
#include <gtest/gtest.h>

#include <cstdio>

#include "builder/build_job.hpp"
#include "builder/scene_loader.hpp"
#include "builder/store_verifier.hpp"
#include "client/shadow_map.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/testing_support.hpp"
#include "tests/verified_build.hpp"

namespace shadowtiles {
namespace {

struct SceneCase {
  testing::SharedSceneCase scene;
  double sun_elevation;
};

class SstAllScenesAt4096 : public ::testing::TestWithParam<SceneCase> {};

TEST_P(SstAllScenesAt4096, EveryTexelInsideItsInterval) {
  const SceneCase& c = GetParam();
  constexpr uint32_t kResolution = 4096, kTile = 1024;
  const std::vector<store::Method> methods{store::Method::mh, store::Method::sst};
  testing::TempDir dir;
  const BuildConfig config = testing::shared_scene_config(c.scene, dir.path() / "s", kResolution, kTile, methods, 135,
                                                         c.sun_elevation);
  auto verified = testing::build_and_verify_every_texel(config, methods);
  ASSERT_TRUE(verified.has_value());
  const auto& bytes = verified->stats["bytes_by_method"];
  std::printf("[ figures  ] %s 4096^2: sst %llu bytes, mh %llu bytes, %llu texels checked\n", c.scene.file,
              (unsigned long long)bytes["sst"].get<uint64_t>(), (unsigned long long)bytes["mh"].get<uint64_t>(),
              (unsigned long long)verified->texels);
}

INSTANTIATE_TEST_SUITE_P(
    SharedScenes, SstAllScenesAt4096,
    ::testing::Values(SceneCase{{"bunny/stanford-bunny.obj", UpAxis::y, false}, 45},
                      SceneCase{{"nefertiti/nefertiti.obj", UpAxis::z, false}, 45},
                      SceneCase{{"fzk_haus/fzk_haus.obj", UpAxis::y, false}, 45},
                      SceneCase{{"dragon_res2/dragon_vrip_res2.ply", UpAxis::y, false}, 45},
                      SceneCase{{"terragen/RealisticTerrain.ply", UpAxis::z, true}, 30},
                      SceneCase{{"oahu/oahu_w158n21.ply", UpAxis::z, true}, 30},
                      SceneCase{{"honolulu_airport/honolulu_airport_harbour.ply", UpAxis::z, false}, 30}));

}  // namespace
}  // namespace shadowtiles
