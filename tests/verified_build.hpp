// Builds a store from a config in-process, then runs the exhaustive verifier (builder/store_verifier)
// on it and asserts that every texel of every listed method was checked, lies inside its interval and
// answers its receiver correctly. Shared by the lossless-store tests (MH family, SST, long variants).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "builder/build_job.hpp"
#include "builder/scene_loader.hpp"
#include "builder/store_verifier.hpp"
#include "client/shadow_map.hpp"

namespace shadowtiles::testing {

struct VerifiedBuild {
  nlohmann::json stats;  // the build's summary stats (bytes_by_method, ...)
  uint64_t texels = 0;   // texels the verifier checked per method
};

// nullopt (with a test failure recorded) when the build, the open, the scene load or the verify fails.
inline std::optional<VerifiedBuild> build_and_verify_every_texel(const BuildConfig& config,
                                                                 const std::vector<store::Method>& methods) {
  auto summary = run_build(config);
  EXPECT_TRUE(summary.ok()) << summary.error().message;
  if (!summary.ok()) return std::nullopt;
  auto map = ShadowMap::open(config.store_path);
  EXPECT_TRUE(map.ok()) << map.error().message;
  if (!map.ok()) return std::nullopt;
  LoadOptions load;
  load.up = config.load.up;
  load.heightfield_meshes = (*map)->meta().heightfield_meshes;
  auto loaded = load_scene(config.scene_path, load);
  EXPECT_TRUE(loaded.ok());
  if (!loaded.ok()) return std::nullopt;
  auto report = verify_store(**map, *loaded, methods);
  EXPECT_TRUE(report.ok()) << report.error().message;
  if (!report.ok()) return std::nullopt;
  const uint64_t texels = uint64_t(*config.resolution) * *config.resolution;
  for (store::Method m : methods) {
    const MethodVerification& v = report->methods.at(m);
    EXPECT_EQ(v.texels, texels) << "every texel of the map is checked";
    EXPECT_EQ(v.outside, 0u) << store::method_name(m) << ": " << v.first_violation;
    EXPECT_EQ(v.wrong_answers, 0u) << store::method_name(m);
  }
  return VerifiedBuild{summary->stats, texels};
}

}  // namespace shadowtiles::testing
