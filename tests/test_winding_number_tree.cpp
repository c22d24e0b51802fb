// WindingNumberTree (builder/winding_number_tree.hpp) against the brute-force sum winding_number():
// on the bunny scan (open: holes in its base), near its surface on both sides (where the nearly
// closed test evaluates it), far away and inside; on a random triangle soup with non-manifold and
// inconsistently oriented triangles (boundaries with net uses of 2 and more). Its speed is the
// build's (docs/build-time.md), not a test's.
#include <gtest/gtest.h>

#include <random>

#include "builder/nearly_closed_meshes.hpp"
#include "builder/scene_loader.hpp"
#include "builder/winding_number_tree.hpp"
#include "codec/vec3_math.hpp"
#include "tests/testing_support.hpp"

namespace st = shadowtiles;
using st::Vec3;

namespace {

std::vector<Vec3> probes_near(const std::vector<Vec3>& vertices, const std::vector<std::array<uint32_t, 3>>& triangles,
                              size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Vec3> probes;
  for (size_t i = 0; i < count; ++i) {
    const auto& t = triangles[rng() % triangles.size()];
    const Vec3 &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
    const Vec3 n = st::cross(st::sub(b, a), st::sub(c, a));
    const double length = st::norm(n);
    const double eps = (i % 2 ? 0.01 : -0.01) * std::sqrt(0.5 * length);  // as the nearly closed test
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = (a[k] + b[k] + c[k]) / 3 + eps * n[k] / length;
    probes.push_back(p);
  }
  return probes;
}

}  // namespace

TEST(WindingNumberTree, EqualsTheBruteForceSumOnTheBunnyScan) {
  st::LoadOptions load;
  load.up = st::UpAxis::y;
  // close_nearly_closed stays off: the scan as stored, open, holes in its base.
  auto scene = st::load_scene(st::testing::shared_scene("bunny/stanford-bunny.obj"), load);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  const auto& triangles = scene->triangles;
  ASSERT_GT(triangles.size(), 50000u);
  const st::WindingNumberTree tree(scene->vertices, triangles);
  std::vector<Vec3> probes = probes_near(scene->vertices, triangles, 200, 1);
  const auto& b = scene->bounds;
  Vec3 mid, size;
  for (int k = 0; k < 3; ++k) mid[k] = 0.5 * (b.min[k] + b.max[k]), size[k] = b.max[k] - b.min[k];
  probes.push_back(mid);                                               // inside the body
  probes.push_back({mid[0] + 3 * size[0], mid[1], mid[2]});            // far outside
  probes.push_back({mid[0], b.min[1] + 0.02 * size[1], mid[2]});       // near the holed base
  for (const Vec3& p : probes) {
    const double brute = st::winding_number(scene->vertices, triangles, p);
    EXPECT_NEAR(tree(p), brute, 1e-9) << p[0] << "," << p[1] << "," << p[2];
  }
  // Near-surface probes must still see the whole integer part: just inside is ~1, just outside ~0.
  EXPECT_NEAR(tree(mid), 1.0, 0.1);
}

TEST(WindingNumberTree, EqualsTheBruteForceSumOnASoupWithNonManifoldEdges) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Vec3> vertices;
  for (int i = 0; i < 300; ++i) vertices.push_back({unit(rng), unit(rng), unit(rng)});
  std::vector<std::array<uint32_t, 3>> triangles;
  for (int i = 0; i < 2000; ++i) {
    const uint32_t a = rng() % 300, b = rng() % 300, c = rng() % 300;
    if (a == b || b == c || a == c) continue;
    triangles.push_back({a, b, c});
    if (i % 5 == 0) triangles.push_back({a, b, c});  // repeated: edges used 2x in one direction
    if (i % 7 == 0) triangles.push_back({b, a, c});  // flipped twin: its edges cancel
  }
  const st::WindingNumberTree tree(vertices, triangles);
  for (int i = 0; i < 300; ++i) {
    const Vec3 p{3 * unit(rng), 3 * unit(rng), 3 * unit(rng)};
    EXPECT_NEAR(tree(p), st::winding_number(vertices, triangles, p), 1e-9) << i;
  }
  const st::WindingNumberTree empty(vertices, {});
  EXPECT_EQ(empty({0, 0, 0}), 0.0);
}
