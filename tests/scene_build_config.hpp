// Build configs of real shared scenes for tests that build stores in-process: one place for the
// scene's file, up axis, heightfield flag, sun and tiling, so each test states only what it varies.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include <gtest/gtest.h>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles::testing {

struct SharedSceneCase {
  const char* file;  // under ../shared/scenes
  UpAxis up;
  bool heightfield;  // every mesh declared a heightfield (terrains)
};

// Every stored method, raw first.
inline const std::vector<store::Method> kEveryMethod = {store::Method::raw,  store::Method::mh,
                                                        store::Method::mmh,  store::Method::dagmh,
                                                        store::Method::cpvs, store::Method::sst};

inline BuildConfig shared_scene_config(const SharedSceneCase& scene, const std::filesystem::path& store,
                                       uint32_t resolution, uint32_t tile, std::vector<store::Method> methods,
                                       double sun_azimuth = 135, double sun_elevation = 40) {
  BuildConfig config;
  config.scene_path = shared_scene(scene.file);
  config.store_path = store;
  config.resolution = resolution;
  config.tile_size = tile;
  config.load.up = scene.up;
  if (scene.heightfield) config.load.heightfield_meshes = {"*"};
  config.light_direction = *light_direction_from_sun(sun_azimuth, sun_elevation, scene.up);
  config.methods = std::move(methods);
  return config;
}

// The small fzk_haus store the client-side tests (ShadowMap batch and concurrency, the C API) build
// once per suite: sun at azimuth 120, elevation 35, tiles 64.
inline BuildConfig fzk_haus_config(const std::filesystem::path& store, uint32_t resolution,
                                   std::vector<store::Method> methods) {
  return shared_scene_config({"fzk_haus/fzk_haus.obj", UpAxis::y, false}, store, resolution, 64, std::move(methods),
                             120, 35);
}

// A suite fixture holding one store built once for all its tests and the query points they share:
// the derived suite's SetUpTestSuite builds into store() and fills points_ (build_fzk_haus_store does
// both for the small fzk_haus store); both are freed after the suite. (One set of statics per derived
// suite.)
template <typename Suite>
class BuiltStoreSuite : public ::testing::Test {
 protected:
  // Builds fzk_haus_config(store(), resolution, every method) and keeps `receivers` surface
  // receivers of the scene (seeded) as points_. Call with ASSERT_NO_FATAL_FAILURE.
  static void build_fzk_haus_store(uint32_t resolution, size_t receivers, uint64_t seed) {
    dir_ = new TempDir();
    const BuildConfig config = fzk_haus_config(store(), resolution, kEveryMethod);
    ASSERT_TRUE(run_build(config).ok());
    auto scene = load_scene(config.scene_path, config.load);
    ASSERT_TRUE(scene.ok());
    points_ = new std::vector<Vec3>;
    for (const Receiver& r : sample_receivers(*scene, receivers, seed)) points_->push_back(r.position);
  }
  static void TearDownTestSuite() {
    delete points_;
    points_ = nullptr;
    delete dir_;
    dir_ = nullptr;
  }
  static std::filesystem::path store() { return dir_->path() / "store"; }
  static inline TempDir* dir_ = nullptr;
  static inline std::vector<Vec3>* points_ = nullptr;
};

}  // namespace shadowtiles::testing
