// Dual depth with Embree on analytic scenes built here: entry/exit of closed boxes, open quads,
// unions of intersecting boxes, heightfields, misses, and tile-local coordinates on large maps.
#include <gtest/gtest.h>

#include <cmath>

#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/scene.hpp"

namespace shadowtiles {
namespace {

using Triangles = std::vector<std::array<uint32_t, 3>>;

// Axis-aligned box, faces counter-clockwise seen from outside (vertex i = x + 2y + 4z bits).
void add_box(Scene& scene, const std::string& name, Vec3 lo, Vec3 hi, bool flip = false) {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  Triangles t{{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
              {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  if (flip)
    for (auto& tri : t) std::swap(tri[1], tri[2]);
  scene.add_mesh(name, v, t);
}

void add_quad(Scene& scene, const std::string& name, double x0, double y0, double x1, double y1, double z,
              bool heightfield = false) {
  std::vector<Vec3> v{{x0, y0, z}, {x1, y0, z}, {x0, y1, z}, {x1, y1, z}};
  scene.add_mesh(name, v, Triangles{{0, 1, 3}, {0, 3, 2}}, heightfield);
}

struct Rendered {
  LightFrame frame;
  TileIntervals tile;
  DualDepthStats stats;
};

// Renders the whole map as one tile with the sun straight above (light travels -z).
Rendered render(const Scene& scene, uint32_t resolution = 64, float exit_margin = 0) {
  auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, resolution);
  EXPECT_TRUE(frame.ok());
  auto layout = TileLayout::make(resolution, resolution);
  LightSpaceScene light_scene(scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  EXPECT_TRUE(device.ok());
  DualDepthRenderer renderer(*device, light_scene, {exit_margin});
  Rendered out{*frame, {}, {}};
  auto tile = renderer.render({0, 0}, &out.stats);
  EXPECT_TRUE(tile.ok());
  out.tile = std::move(*tile);
  return out;
}

// The texel under world (x, y) and the normalised depth of world height z.
DepthInterval texel_at(const Rendered& r, double x, double y) {
  LightSpacePoint p = r.frame.to_light({x, y, 0});
  return r.tile.at(uint32_t(p.u), uint32_t(p.v));
}
float depth_of(const Rendered& r, double z) { return float(r.frame.to_light({0, 0, z}).depth); }

TEST(DualDepth, ClosedBoxGivesEntryAndExit) {
  Scene scene;
  add_box(scene, "box", {0, 0, 2}, {10, 10, 5});
  ASSERT_EQ(scene.meshes[0].kind, MeshKind::closed);
  Rendered r = render(scene);
  DepthInterval i = texel_at(r, 5.1, 4.9);
  EXPECT_NEAR(i.lower, depth_of(r, 5), 1e-6);
  EXPECT_NEAR(i.upper, depth_of(r, 2), 1e-6);
  EXPECT_GT(i.upper - i.lower, 0.5f) << "the box is most of the depth range";
  EXPECT_GT(r.stats.exits, r.stats.rays / 2);
}

TEST(DualDepth, ExitMarginPullsTheExitBack) {
  Scene scene;
  add_box(scene, "box", {0, 0, 2}, {10, 10, 5});
  Rendered r = render(scene, 64, 0.01f);
  DepthInterval i = texel_at(r, 5.1, 4.9);
  EXPECT_NEAR(i.upper, depth_of(r, 2) - 0.01f, 1e-6);
}

TEST(DualDepth, OpenQuadIsOneSided) {
  Scene scene;
  add_quad(scene, "roof", 0, 0, 10, 10, 3);
  add_quad(scene, "floor", 0, 0, 10, 10, 0);
  ASSERT_EQ(scene.meshes[0].kind, MeshKind::open);
  Rendered r = render(scene);
  DepthInterval i = texel_at(r, 5.1, 5.1);
  EXPECT_NEAR(i.lower, depth_of(r, 3), 1e-6);
  EXPECT_EQ(i.upper, i.lower) << "open geometry: exit = entry, so the floor below stays shadowed";
}

TEST(DualDepth, BoxWithAFaceMissingIsOpen) {
  Scene scene;
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.push_back({(i & 1) ? 10.0 : 0.0, (i & 2) ? 10.0 : 0.0, (i & 4) ? 5.0 : 2.0});
  Triangles t{{4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  scene.add_mesh("no_bottom", v, t);
  ASSERT_EQ(scene.meshes[0].kind, MeshKind::open);
  Rendered r = render(scene);
  DepthInterval i = texel_at(r, 5.1, 4.9);
  EXPECT_EQ(i.upper, i.lower);
}

TEST(DualDepth, IntersectingBoxesExitTheUnion) {
  Scene scene;
  add_box(scene, "low", {0, 0, 0}, {6, 10, 2});
  add_box(scene, "high", {4, 0, 1}, {10, 10, 3});
  Rendered r = render(scene);
  DepthInterval overlap = texel_at(r, 5.1, 5.1);
  EXPECT_NEAR(overlap.lower, depth_of(r, 3), 1e-6);
  EXPECT_NEAR(overlap.upper, depth_of(r, 0), 1e-6) << "exit of the union, not of the first box";
  DepthInterval high_only = texel_at(r, 8.1, 5.1);
  EXPECT_NEAR(high_only.lower, depth_of(r, 3), 1e-6);
  EXPECT_NEAR(high_only.upper, depth_of(r, 1), 1e-6);
}

TEST(DualDepth, StackedBoxesWithAGapExitTheFirst) {
  Scene scene;
  add_box(scene, "top", {0, 0, 6}, {10, 10, 8});
  add_box(scene, "bottom", {0, 0, 0}, {10, 10, 2});
  Rendered r = render(scene);
  DepthInterval i = texel_at(r, 5.1, 5.1);
  EXPECT_NEAR(i.lower, depth_of(r, 8), 1e-6);
  EXPECT_NEAR(i.upper, depth_of(r, 6), 1e-6) << "a receiver in the gap must stay shadowed";
}

TEST(DualDepth, InsideOutBoxIsConservative) {
  Scene scene;
  add_box(scene, "inverted", {0, 0, 2}, {10, 10, 5}, /*flip=*/true);
  Rendered r = render(scene);
  DepthInterval i = texel_at(r, 5.1, 4.9);
  EXPECT_NEAR(i.lower, depth_of(r, 5), 1e-6);
  EXPECT_EQ(i.upper, i.lower) << "first hit back-facing: no exit is trusted";
}

TEST(DualDepth, HeightfieldIsSolidToTheFarPlane) {
  Scene scene;
  add_quad(scene, "terrain", 0, 0, 10, 10, 1, /*heightfield=*/true);
  add_box(scene, "tall", {0, 0, 0}, {1, 1, 6});  // only to give the scene depth
  Rendered r = render(scene);
  DepthInterval i = texel_at(r, 6.1, 6.1);
  EXPECT_NEAR(i.lower, depth_of(r, 1), 1e-6);
  EXPECT_EQ(i.upper, 1.0f);
}

TEST(DualDepth, HeightfieldFarPlaneExitIsPulledBackByTheMargin) {
  // Receivers beyond the far plane are queried as on it: under terrain they must stay shadowed for
  // any bias up to the exit margin, like receivers on any other exit surface.
  Scene scene;
  add_quad(scene, "terrain", 0, 0, 10, 10, 1, /*heightfield=*/true);
  add_box(scene, "tall", {0, 0, 0}, {1, 1, 6});
  Rendered r = render(scene, 64, 0.01f);
  DepthInterval i = texel_at(r, 6.1, 6.1);
  EXPECT_NEAR(i.lower, depth_of(r, 1), 1e-6);
  EXPECT_EQ(i.upper, 1.0f - 0.01f);
}

TEST(DualDepth, HeightfieldHillShadowsTheValleyBehindIt) {
  // A ridge in terrain under a low sun: the ray enters the sunlit slope and leaves the far slope;
  // the valley floor behind is below that exit and must stay shadowed (the solid is not "everything
  // below the first hit" unless the sun is overhead).
  Scene scene;
  std::vector<Vec3> v{{0, 0, 0}, {5, 0, 5}, {10, 0, 0}, {30, 0, 0}, {0, 10, 0}, {5, 10, 5}, {10, 10, 0}, {30, 10, 0}};
  Triangles t{{0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}};
  scene.add_mesh("terrain", v, t, /*heightfield=*/true);
  Vec3 light{1, 0, -0.3};  // sun low in the -x direction
  auto frame = LightFrame::fit(light, scene.bounds, 256);
  ASSERT_TRUE(frame.ok());
  auto layout = TileLayout::make(256, 256);
  LightSpaceScene light_scene(scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  DualDepthRenderer renderer(*device, light_scene);
  auto tile = renderer.render({0, 0});
  ASSERT_TRUE(tile.ok());
  LightSpacePoint valley = frame->to_light({15, 5, 0});
  const DepthInterval& i = tile->at(uint32_t(valley.u), uint32_t(valley.v));
  EXPECT_LT(i.lower, valley.depth) << "the ridge is in front of the valley";
  EXPECT_LT(i.upper, valley.depth) << "the exit is on the ridge's far slope, not at the far plane";
  LightSpacePoint open_ground = frame->to_light({28, 5, 0});
  const DepthInterval& g = tile->at(uint32_t(open_ground.u), uint32_t(open_ground.v));
  EXPECT_NEAR(g.lower, open_ground.depth, 1e-3) << "sunlit ground beyond the shadow";
  EXPECT_EQ(g.upper, 1.0f) << "terrain solid to the far plane below a lit surface";
}

TEST(DualDepth, MissesAreFullyLit) {
  Scene scene;
  add_box(scene, "small", {0, 0, 0}, {1, 1, 1});
  add_box(scene, "far", {9, 9, 0}, {10, 10, 1});
  Rendered r = render(scene);
  DepthInterval miss = texel_at(r, 5, 5);
  EXPECT_EQ(miss.lower, 1.0f);
  EXPECT_TRUE(std::isinf(miss.upper));
  EXPECT_LT(r.stats.hits, r.stats.rays);
}

TEST(DualDepth, TilesOfALargeMapMatchTheWholeMap) {
  // The same scene rendered as 4x4 tiles and as one tile gives bit-identical intervals: per-tile
  // culling loses nothing at the seams, and hit depths are re-evaluated from each triangle's global
  // plane, so the tile-local float coordinates of each BVH leave no rounding trace.
  Scene scene;
  add_box(scene, "a", {0, 0, 0}, {3.3, 7.7, 2});
  add_box(scene, "b", {2.1, 1.5, 1}, {9.9, 4.4, 3});
  add_quad(scene, "sheet", -1, -1, 11, 11, -1);
  auto frame = LightFrame::fit({0.2, -0.3, -1}, scene.bounds, 256);
  ASSERT_TRUE(frame.ok());
  auto device = EmbreeDevice::create();
  ASSERT_TRUE(device.ok());
  auto whole_layout = TileLayout::make(256, 256);
  LightSpaceScene whole_scene(scene, *frame, *whole_layout);
  DualDepthRenderer whole_renderer(*device, whole_scene);
  auto whole = whole_renderer.render({0, 0});
  ASSERT_TRUE(whole.ok());
  auto tiled_layout = TileLayout::make(256, 64);
  LightSpaceScene tiled_scene(scene, *frame, *tiled_layout);
  DualDepthRenderer tiled_renderer(*device, tiled_scene);
  int mismatches = 0;
  for (uint32_t ty = 0; ty < 4; ++ty)
    for (uint32_t tx = 0; tx < 4; ++tx) {
      auto tile = tiled_renderer.render({tx, ty});
      ASSERT_TRUE(tile.ok());
      for (uint32_t v = 0; v < 64; ++v)
        for (uint32_t u = 0; u < 64; ++u) {
          const DepthInterval& a = tile->at(u, v);
          const DepthInterval& b = whole->at(tx * 64 + u, ty * 64 + v);
          if (a.lower != b.lower || a.upper != b.upper) ++mismatches;
        }
    }
  EXPECT_EQ(mismatches, 0);
}

}  // namespace
}  // namespace shadowtiles
