// The far plane (issue #8, STABILITY.md scenario 7): the light frame keeps every surface a margin
// short of depth 1 and queries clamp a receiver's depth to 1, so a point beyond the far plane is
// lit where nothing lies above it (a miss, stored value 1) and stays shadowed under any surface,
// however deep: open, closed or heightfield, for every method, point and PCF.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "builder/build_job.hpp"
#include "builder/tile_encoder.hpp"
#include "client/shadow_map.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

std::vector<store::Method> built_methods() {
  std::vector<store::Method> methods;
  for (store::Method m : store::all_methods())
    if (builder_supports(m)) methods.push_back(m);
  return methods;
}

Vec3 unit(const Vec3& v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / n, v[1] / n, v[2] / n};
}

// `p` moved `distance` along the light: the same texel, deeper.
Vec3 along_light(const Vec3& p, const Vec3& light, double distance) {
  const Vec3 d = unit(light);
  return {p[0] + distance * d[0], p[1] + distance * d[1], p[2] + distance * d[2]};
}

// A 64^2 map of `obj` in tiles of `tile_size`, every method.
std::unique_ptr<ShadowMap> build(const testing::TempDir& dir, const std::string& name, const std::string& obj,
                                 const Vec3& light, uint32_t tile_size,
                                 const std::vector<std::string>& heightfields = {}) {
  const auto scene = dir.path() / (name + ".obj");
  std::ofstream(scene) << obj;
  BuildConfig config;
  config.scene_path = scene;
  config.store_path = dir.path() / name;
  config.light_direction = light;
  config.resolution = 64;
  config.tile_size = tile_size;
  config.methods = built_methods();
  config.load.heightfield_meshes = heightfields;
  config.overwrite = true;
  auto summary = run_build(config);
  EXPECT_TRUE(summary.ok()) << summary.error().message;
  auto map = ShadowMap::open(config.store_path);
  EXPECT_TRUE(map.ok());
  return map ? std::move(*map) : nullptr;
}

// Every method, point query and PCF 3x3, must answer `lit` at `p`, which must lie beyond the far plane
// on a stored tile.
void expect_everywhere(const ShadowMap& map, const Vec3& p, bool lit, const std::string& what) {
  ASSERT_GT(map.frame().to_light(p).depth, 1.0) << what << ": the probe must lie beyond the far plane";
  for (store::Method m : map.meta().methods) {
    auto point = map.query(p, m);
    ASSERT_TRUE(point.ok()) << point.error().message;
    EXPECT_FALSE(point->outside_map) << what;
    EXPECT_FALSE(point->empty_tile) << what << ": a stored texel (a miss beside geometry), not an empty tile";
    EXPECT_EQ(point->lit, lit) << what << ", " << store::method_name(m) << " point query";
    auto pcf = map.query_pcf(p, m, 3);
    ASSERT_TRUE(pcf.ok()) << pcf.error().message;
    EXPECT_EQ(*pcf, lit ? 1.0 : 0.0) << what << ", " << store::method_name(m) << " PCF 3x3";
  }
}

// A flat scene: its depth range used to be its 1e-5 padding, so a point 1 unit below it had depth
// ~1e5 and, beside the triangle, compared greater than a miss's stored 1. Now the far margin gives
// it depth, and points further below than that are beyond the far plane.
TEST(FarPlane, BelowAFlatSceneBesideItIsLitAndUnderItShadowed) {
  testing::TempDir dir;
  const Vec3 sun_overhead{0, 0, -1};
  // One tile, so the texels beside the triangle are stored misses (not an empty tile).
  auto map = build(dir, "flat", "v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n", sun_overhead, 64);
  ASSERT_TRUE(map);
  for (double below : {100.0, 1e4}) {
    const std::string far = ", " + std::to_string(int(below)) + " below";
    expect_everywhere(*map, {9, 9, -below}, true, "beside the triangle" + far);
    expect_everywhere(*map, {2, 2, -below}, false, "under the triangle" + far);
  }
}

// Under an oblique sun, the deepest surfaces of three kinds: an open floor, the bottom of a closed
// box and a heightfield's terrain (solid to the far plane). Points far beyond each stay shadowed;
// a point beyond the far plane beside them all is lit.
TEST(FarPlane, DeepestSurfacesOfEveryKindShadowWhatLiesBeyond) {
  testing::TempDir dir;
  const Vec3 light{0.3, 0.2, -1};
  const std::string obj =
      "o floor\nv 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n"                         // open, x + y <= 10
      "o box\nv 7 7 -2\nv 9 7 -2\nv 7 9 -2\nv 9 9 -2\nv 7 7 0\nv 9 7 0\nv 7 9 0\nv 9 9 0\n"
      "f 4 6 7\nf 4 7 5\nf 8 9 11\nf 8 11 10\nf 4 5 9\nf 4 9 8\n"               // closed, below z = 0
      "f 6 10 11\nf 6 11 7\nf 4 8 10\nf 4 10 6\nf 5 7 11\nf 5 11 9\n"
      "o terrain\nv -6 0 -3\nv -2 0 -3\nv -6 4 -3\nv -2 4 -3\nf 12 13 15\nf 12 15 14\n";
  auto map = build(dir, "kinds", obj, light, 32, {"terrain"});  // 2 x 2 tiles
  ASSERT_TRUE(map);
  for (double distance : {50.0, 1e4}) {
    const std::string far = " (" + std::to_string(int(distance)) + " along the light)";
    expect_everywhere(*map, along_light({2, 2, 0}, light, distance), false, "under the open floor" + far);
    expect_everywhere(*map, along_light({8, 8, -2}, light, distance), false, "under the closed box" + far);
    expect_everywhere(*map, along_light({-4, 2, -3}, light, distance), false, "under the heightfield" + far);
    expect_everywhere(*map, along_light({9, 2.5, 0}, light, distance), true, "beside everything" + far);
  }
}

}  // namespace
}  // namespace shadowtiles
