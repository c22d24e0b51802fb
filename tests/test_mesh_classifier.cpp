// Mesh classifier (builder/mesh_classifier.hpp) and Scene::add_mesh (builder/scene.hpp).
#include "builder/mesh_classifier.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "builder/scene.hpp"

namespace shadowtiles {
namespace {

using Triangles = std::vector<std::array<uint32_t, 3>>;

// Unit cube, 8 shared vertices, 12 triangles, counter-clockwise seen from outside.
std::vector<Vec3> cube_vertices(double offset = 0) {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i)
    v.push_back({double(i & 1) + offset, double((i >> 1) & 1), double((i >> 2) & 1)});
  return v;
}
Triangles cube_triangles() {
  // Faces as quads (outward counter-clockwise), split into two triangles each.
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  Triangles t;
  for (const auto& q : quads) {
    t.push_back({q[0], q[1], q[2]});
    t.push_back({q[0], q[2], q[3]});
  }
  return t;
}
// The same cube as importers deliver it: each triangle with vertices of its own (36, positions
// repeated), as when every face carries its own normal or uv.
struct SplitMesh {
  std::vector<Vec3> vertices;
  Triangles triangles;
};
SplitMesh split_cube() {
  const std::vector<Vec3> shared = cube_vertices();
  SplitMesh mesh;
  for (const auto& tri : cube_triangles()) {
    const uint32_t base = uint32_t(mesh.vertices.size());
    for (uint32_t k : tri) mesh.vertices.push_back(shared[k]);
    mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return mesh;
}

TEST(MeshClassifier, CubeIsClosedWithPositiveVolume) {
  const auto c = classify_mesh(cube_vertices(), cube_triangles());
  EXPECT_EQ(c.kind, MeshKind::closed);
  EXPECT_EQ(c.edges, 18u);  // 12 cube edges + 6 face diagonals
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.non_manifold_edges, 0u);
  EXPECT_EQ(c.misoriented_edges, 0u);
  EXPECT_NEAR(c.signed_volume, 1.0, 1e-12);
}

TEST(MeshClassifier, InsideOutCubeIsClosedWithNegativeVolume) {
  Triangles t = cube_triangles();
  for (auto& tri : t) std::swap(tri[1], tri[2]);
  const auto c = classify_mesh(cube_vertices(), t);
  EXPECT_EQ(c.kind, MeshKind::closed);
  EXPECT_NEAR(c.signed_volume, -1.0, 1e-12);
}

TEST(MeshClassifier, CubeMissingAFaceIsOpenWithFourBoundaryEdges) {
  Triangles t = cube_triangles();
  t.resize(10);  // drop the last face (two triangles)
  const auto c = classify_mesh(cube_vertices(), t);
  EXPECT_EQ(c.kind, MeshKind::open);
  EXPECT_EQ(c.boundary_edges, 4u);
  EXPECT_EQ(c.non_manifold_edges, 0u);
  EXPECT_EQ(c.misoriented_edges, 0u);
}

TEST(MeshClassifier, FlippedFaceIsMisoriented) {
  Triangles t = cube_triangles();
  std::swap(t[0][1], t[0][2]);  // flip both triangles of face 0
  std::swap(t[1][1], t[1][2]);
  const auto c = classify_mesh(cube_vertices(), t);
  EXPECT_EQ(c.kind, MeshKind::open);
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.non_manifold_edges, 0u);
  EXPECT_EQ(c.misoriented_edges, 4u);  // the face's 4 border edges; its diagonal is internally consistent
}

TEST(MeshClassifier, SingleFlippedTriangleIsMisoriented) {
  Triangles t = cube_triangles();
  std::swap(t[0][1], t[0][2]);
  const auto c = classify_mesh(cube_vertices(), t);
  EXPECT_EQ(c.kind, MeshKind::open);
  EXPECT_EQ(c.misoriented_edges, 3u);
}

TEST(MeshClassifier, TwoCubesSharingAnEdgeAreNonManifold) {
  // Second cube offset by (1, 1, 0): shares the cube edge x = 1, y = 1 (z from 0 to 1).
  std::vector<Vec3> v = cube_vertices();
  for (Vec3 p : cube_vertices()) v.push_back({p[0] + 1, p[1] + 1, p[2]});
  Triangles t = cube_triangles();
  for (auto tri : cube_triangles()) t.push_back({tri[0] + 8, tri[1] + 8, tri[2] + 8});
  const auto c = classify_mesh(v, t);
  EXPECT_EQ(c.kind, MeshKind::open);
  EXPECT_EQ(c.non_manifold_edges, 1u);  // the shared edge has four triangles
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.misoriented_edges, 0u);
}

TEST(MeshClassifier, SplitVerticesAreWelded) {
  auto [v, t] = split_cube();
  v[0][0] = -0.0;  // -0.0 and 0.0 are the same position
  ASSERT_EQ(v.size(), 36u);
  uint32_t unique = 0;
  (void)weld_positions(v, &unique);
  EXPECT_EQ(unique, 8u);
  const auto c = classify_mesh(v, t);
  EXPECT_EQ(c.kind, MeshKind::closed);
  EXPECT_EQ(c.boundary_edges, 0u);
}

TEST(MeshClassifier, TetrahedronIsClosed) {
  const std::vector<Vec3> v{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const Triangles t{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const auto c = classify_mesh(v, t);
  EXPECT_EQ(c.kind, MeshKind::closed);
  EXPECT_EQ(c.edges, 6u);
  EXPECT_NEAR(c.signed_volume, 1.0 / 6.0, 1e-12);
}

TEST(MeshClassifier, SingleTriangleAndEmptyAreOpen) {
  const std::vector<Vec3> v{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const auto one = classify_mesh(v, Triangles{{0, 1, 2}});
  EXPECT_EQ(one.kind, MeshKind::open);
  EXPECT_EQ(one.boundary_edges, 3u);
  EXPECT_EQ(classify_mesh(v, Triangles{}).kind, MeshKind::open);
  EXPECT_EQ(classify_mesh({}, Triangles{}).kind, MeshKind::open);
}

TEST(MeshClassifier, BadIndicesAreSkippedNotTrusted) {
  Triangles t = cube_triangles();
  t.push_back({0, 1, 99});  // out of range
  t.push_back({0, 0, 1});   // repeated
  const auto c = classify_mesh(cube_vertices(), t);
  EXPECT_EQ(c.skipped_triangles, 2u);
  EXPECT_EQ(c.kind, MeshKind::open);  // a malformed mesh is never trusted as closed
  EXPECT_EQ(c.boundary_edges, 0u);
}

// ---- Scene::add_mesh ----

TEST(SceneAddMesh, ClassifiesAndBoundsCube) {
  Scene scene;
  EXPECT_EQ(scene.add_mesh("cube", cube_vertices(10), cube_triangles()), 0u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::closed);
  EXPECT_NEAR(scene.meshes[0].signed_volume, 1.0, 1e-12);
  EXPECT_EQ(scene.triangle_count(), 12u);
  EXPECT_EQ(scene.vertices.size(), 8u);
  EXPECT_EQ(scene.bounds.min, (Vec3{10, 0, 0}));  // not stuck at the default origin
  EXPECT_EQ(scene.bounds.max, (Vec3{11, 1, 1}));
  EXPECT_STREQ(mesh_kind_name(scene.meshes[0].kind), "closed");
}

TEST(SceneAddMesh, SecondMeshOffsetsIndicesAndGrowsBounds) {
  Scene scene;
  (void)scene.add_mesh("a", cube_vertices(), cube_triangles());
  Triangles open = cube_triangles();
  open.pop_back();
  (void)scene.add_mesh("b", cube_vertices(5), open);
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.meshes[1].first_triangle, 12u);
  EXPECT_EQ(scene.meshes[1].triangle_count, 11u);
  EXPECT_EQ(scene.meshes[1].kind, MeshKind::open);
  EXPECT_EQ(scene.meshes[1].boundary_edges, 3u);
  EXPECT_EQ(scene.triangle_mesh.size(), 23u);
  EXPECT_EQ(scene.triangle_mesh[12], 1u);
  for (size_t i = 12; i < scene.triangles.size(); ++i)
    for (uint32_t index : scene.triangles[i]) {
      ASSERT_GE(index, 8u);
      ASSERT_LT(index, scene.vertices.size());
      EXPECT_GE(scene.vertices[index][0], 5.0);
    }
  EXPECT_EQ(scene.bounds.min, (Vec3{0, 0, 0}));
  EXPECT_EQ(scene.bounds.max, (Vec3{6, 1, 1}));
}

TEST(SceneAddMesh, DropsMalformedTriangles) {
  std::vector<Vec3> v = cube_vertices();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  v.push_back({nan, 0, 0});      // 8
  v.push_back({0, inf, 0});      // 9
  v.push_back({0.5, 0.5, 0});    // 10: on the edge 0-3 diagonal of face z = 0
  v.push_back({1e9, 1e9, 1e9});  // 11: unused, must not reach the bounds
  Triangles t = cube_triangles();
  t.push_back({0, 1, 8});   // NaN corner
  t.push_back({0, 9, 1});   // infinite corner
  t.push_back({0, 1, 42});  // out of range
  t.push_back({2, 2, 3});   // repeated index
  t.push_back({0, 3, 10});  // collinear: zero area
  Scene scene;
  EXPECT_EQ(scene.add_mesh("dirty", v, t), 5u);
  EXPECT_EQ(scene.meshes[0].dropped_triangles, 5u);
  EXPECT_EQ(scene.triangle_count(), 12u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::closed);  // what is left is the intact cube
  EXPECT_EQ(scene.vertices.size(), 8u);               // unused and dropped-only vertices not stored
  EXPECT_EQ(scene.bounds.max, (Vec3{1, 1, 1}));
}

TEST(SceneAddMesh, ZeroAreaThresholdIsRelative) {
  // A sliver whose height is 1e-6 of its length is kept at any scale; one at 1e-13 is dropped.
  for (double scale : {1e-6, 1.0, 1e6}) {
    Scene scene;
    const std::vector<Vec3> v{
        {0, 0, 0}, {scale, 0, 0}, {0.5 * scale, 1e-6 * scale, 0}, {0.5 * scale, 1e-13 * scale, 0}};
    EXPECT_EQ(scene.add_mesh("sliver", v, Triangles{{0, 1, 2}, {0, 1, 3}}), 1u) << scale;
  }
}

TEST(SceneAddMesh, HeightfieldIsNotClassified) {
  Scene scene;
  Triangles open = cube_triangles();
  open.resize(2);
  (void)scene.add_mesh("ground", cube_vertices(), open, /*heightfield=*/true);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::heightfield);
  EXPECT_EQ(scene.meshes[0].boundary_edges, 0u);
  EXPECT_STREQ(mesh_kind_name(MeshKind::heightfield), "heightfield");
}

TEST(SceneAddMesh, SplitVerticesAreMergedInTheScene) {
  const auto [v, t] = split_cube();
  Scene scene;
  EXPECT_EQ(scene.add_mesh("split", v, t), 0u);
  EXPECT_EQ(scene.vertices.size(), 8u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::closed);
}

TEST(SceneAddMesh, EmptyMeshIsRecordedAndLeavesBoundsAlone) {
  Scene scene;
  const std::vector<Vec3> v{{5, 5, 5}, {5, 5, 5}, {5, 5, 5}};
  EXPECT_EQ(scene.add_mesh("all-degenerate", v, Triangles{{0, 1, 2}}), 1u);
  (void)scene.add_mesh("cube", cube_vertices(-3), cube_triangles());
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.meshes[0].triangle_count, 0u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);
  EXPECT_EQ(scene.meshes[1].first_triangle, 0u);
  EXPECT_EQ(scene.bounds.min, (Vec3{-3, 0, 0}));
  EXPECT_EQ(scene.bounds.max, (Vec3{-2, 1, 1}));
}

}  // namespace
}  // namespace shadowtiles
