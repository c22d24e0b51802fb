// Scene loader (builder/scene_loader.hpp): real files from ../shared/scenes and Debian's
// assimp-testmodels, node transforms, heightfield matching, and malformed input.
#include "builder/scene_loader.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>

#include "tests/testing_support.hpp"

// assimp 5.2's PLY importer leaks its parse tree when a binary file ends early (an exception path
// inside libassimp; nothing of ours in the stack). Bounded by the file's size, so tolerated:
// LeakSanitizer ignores leaks allocated from within libassimp in this executable only.
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

namespace shadowtiles {
namespace {

using testing::assimp_model;
using testing::shared_scene;
using testing::read_file;
using testing::TempDir;
using testing::write_file;

Scene load_ok(const std::filesystem::path& file, const LoadOptions& options = {},
              LoadStats* stats = nullptr) {
  auto scene = load_scene(file, options, stats);
  EXPECT_TRUE(scene.ok()) << file << ": " << (scene.ok() ? "" : scene.error().message);
  if (!scene.ok()) return Scene{};
  return std::move(scene).value();
}



WorldBounds mesh_bounds(const Scene& scene, const MeshInfo& mesh) {
  WorldBounds b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (uint32_t t = mesh.first_triangle; t < mesh.first_triangle + mesh.triangle_count; ++t)
    for (uint32_t v : scene.triangles[t])
      for (int k = 0; k < 3; ++k) {
        b.min[k] = std::min(b.min[k], scene.vertices[v][k]);
        b.max[k] = std::max(b.max[k], scene.vertices[v][k]);
      }
  return b;
}

void expect_bounds_near(const WorldBounds& b, const Vec3& min, const Vec3& max, double tolerance) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(b.min[k], min[k], tolerance) << "min " << k;
    EXPECT_NEAR(b.max[k], max[k], tolerance) << "max " << k;
  }
}

// The stats agree with the scene they describe.
void expect_consistent(const Scene& scene, const LoadStats& stats) {
  EXPECT_EQ(stats.triangles, scene.triangle_count());
  EXPECT_EQ(stats.meshes, scene.meshes.size());
  EXPECT_EQ(stats.closed_meshes + stats.open_meshes + stats.heightfield_meshes, stats.meshes);
  EXPECT_EQ(scene.triangle_mesh.size(), scene.triangles.size());
  EXPECT_GT(stats.seconds, 0.0);
  uint64_t sum = 0;
  for (const auto& m : scene.meshes) sum += m.triangle_count;
  EXPECT_EQ(sum, scene.triangle_count());
}

// ---- Shared scenes (README: ../shared/scenes/README.md) ----

TEST(SceneLoaderShared, BunnyIsOneOpenMesh) {
  LoadStats stats;
  const Scene scene = load_ok(shared_scene("bunny/stanford-bunny.obj"), {}, &stats);
  expect_consistent(scene, stats);
  EXPECT_EQ(stats.triangles + stats.dropped_triangles, 69451u);
  EXPECT_EQ(stats.dropped_triangles, 0u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);  // holes in the base
  EXPECT_GT(scene.meshes[0].boundary_edges, 0u);
  EXPECT_EQ(scene.meshes[0].misoriented_edges, 0u);
  // y up, about 15 cm tall.
  expect_bounds_near(scene.bounds, {-0.0947, 0.0330, -0.0619}, {0.0610, 0.1873, 0.0588}, 1e-3);
}

TEST(SceneLoaderShared, NefertitiIsClosedAndOutwardFacing) {
  LoadStats stats;
  const Scene scene = load_ok(shared_scene("nefertiti/nefertiti.obj"), {}, &stats);
  expect_consistent(scene, stats);
  EXPECT_EQ(stats.triangles, 99938u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  const MeshInfo& m = scene.meshes[0];
  EXPECT_EQ(m.kind, MeshKind::closed) << m.boundary_edges << " boundary, " << m.non_manifold_edges
                                      << " non-manifold, " << m.misoriented_edges << " misoriented";
  EXPECT_GT(m.signed_volume, 0.0);  // normals outward: exit depths come out right
  EXPECT_EQ(stats.closed_meshes, 1u);
  expect_bounds_near(scene.bounds, {-119.3, -181.3, -247.3}, {119.4, 181.2, 247.3}, 0.1);
}

TEST(SceneLoaderShared, FzkHausHasManyMeshesMostlyOpen) {
  LoadStats stats;
  const Scene scene = load_ok(shared_scene("fzk_haus/fzk_haus.obj"), {}, &stats);
  expect_consistent(scene, stats);
  EXPECT_EQ(stats.triangles + stats.dropped_triangles, 35906u);
  EXPECT_LT(stats.dropped_triangles, 100u);
  EXPECT_GT(stats.meshes, 10u);
  EXPECT_GT(stats.open_meshes, 0u);
  EXPECT_GT(stats.closed_meshes, 0u);  // simple boxes (window frames, posts) are closed
  uint64_t boundary = 0, non_manifold = 0;
  for (const auto& m : scene.meshes) {
    boundary += m.boundary_edges;
    non_manifold += m.non_manifold_edges;
  }
  EXPECT_GT(boundary, 0u);
  EXPECT_GT(non_manifold, 0u);
  // A house: about 18 x 7 x 16 m.
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(scene.bounds.max[k] - scene.bounds.min[k], 5.0);
    EXPECT_LT(scene.bounds.max[k] - scene.bounds.min[k], 30.0);
  }
}

TEST(SceneLoaderShared, OahuBinaryPlyTerrain) {
  LoadStats stats;
  const Scene scene = load_ok(shared_scene("oahu/oahu_w158n21.ply"), {.heightfield_meshes = {"*"}}, &stats);
  expect_consistent(scene, stats);
  EXPECT_EQ(stats.triangles + stats.dropped_triangles, 488959u);
  EXPECT_LT(stats.dropped_triangles, 100u);
  EXPECT_EQ(stats.heightfield_meshes, 1u);
  // z up, metres, about 100 x 80 km, heights from sea level to under 1,300 m (Kaala: 1,227 m).
  EXPECT_NEAR(scene.bounds.max[0] - scene.bounds.min[0], 100e3, 10e3);
  EXPECT_NEAR(scene.bounds.max[1] - scene.bounds.min[1], 80e3, 10e3);
  EXPECT_GT(scene.bounds.min[2], -50.0);
  EXPECT_LT(scene.bounds.max[2], 1300.0);
}

TEST(SceneLoaderShared, OahuIsOpenWhenNotAHeightfield) {
  const Scene scene = load_ok(shared_scene("oahu/oahu_w158n21.ply"));
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);
  EXPECT_GT(scene.meshes[0].boundary_edges, 0u);  // coast and tile seams
}

TEST(SceneLoaderShared, DragonAsciiPlyIsNonManifold) {
  LoadStats stats;
  const Scene scene = load_ok(shared_scene("dragon_res2/dragon_vrip_res2.ply"), {}, &stats);
  expect_consistent(scene, stats);
  EXPECT_EQ(stats.triangles + stats.dropped_triangles, 202520u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);
  EXPECT_GT(scene.meshes[0].non_manifold_edges, 0u);
  EXPECT_NEAR(scene.bounds.max[1] - scene.bounds.min[1], 0.144, 0.01);  // y up, ~14 cm tall
}

TEST(SceneLoaderShared, HonoluluAirport) {
  LoadStats stats;
  const Scene scene = load_ok(shared_scene("honolulu_airport/honolulu_airport_harbour.ply"), {}, &stats);
  expect_consistent(scene, stats);
  EXPECT_EQ(stats.triangles + stats.dropped_triangles, 383116u);
  EXPECT_NEAR(scene.bounds.max[0] - scene.bounds.min[0], 9.5e3, 1e3);
  EXPECT_NEAR(scene.bounds.max[1] - scene.bounds.min[1], 9.8e3, 1e3);
}

TEST(SceneLoaderShared, TerragenTerMatchesItsPlyConversion) {
  LoadStats stats;
  const Scene ter = load_ok(shared_scene("terragen/RealisticTerrain.ter"),
                            {.heightfield_meshes = {"RealisticTerrain"}}, &stats);
  expect_consistent(ter, stats);
  EXPECT_EQ(stats.triangles, 131072u);
  ASSERT_EQ(ter.meshes.size(), 1u);
  EXPECT_EQ(ter.meshes[0].name, "RealisticTerrain");
  EXPECT_EQ(ter.meshes[0].kind, MeshKind::heightfield);
  EXPECT_EQ(ter.vertices.size(), 257u * 257u);
  // z up, metres: 256 cells of 30 m, heights in tens to hundreds of metres.
  expect_bounds_near(ter.bounds, {0, 0, -78.99}, {7680, 7680, 874.53}, 0.01);

  const Scene ply = load_ok(shared_scene("terragen/RealisticTerrain.ply"));
  ASSERT_EQ(ply.triangle_count(), ter.triangle_count());
  expect_bounds_near(ply.bounds, ter.bounds.min, ter.bounds.max, 1e-3);
  // Same heights at the same grid points as the .ply (whose vertex order may differ).
  ASSERT_EQ(ply.vertices.size(), ter.vertices.size());
  std::map<std::pair<long, long>, double> ply_height;
  for (const Vec3& p : ply.vertices) ply_height[{std::lround(p[0]), std::lround(p[1])}] = p[2];
  for (const Vec3& p : ter.vertices) {
    auto it = ply_height.find({std::lround(p[0]), std::lround(p[1])});
    ASSERT_NE(it, ply_height.end()) << p[0] << ", " << p[1];
    ASSERT_NEAR(it->second, p[2], 1e-3) << p[0] << ", " << p[1];
  }
  // Every triangle counter-clockwise seen from above (normals up), like the .ply's.
  auto up = [](const Scene& s) {
    size_t count = 0;
    for (const auto& t : s.triangles) {
      const Vec3 &a = s.vertices[t[0]], &b = s.vertices[t[1]], &c = s.vertices[t[2]];
      count += (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0;
    }
    return count;
  };
  EXPECT_EQ(up(ter), ter.triangle_count());
  EXPECT_EQ(up(ply), ply.triangle_count());
  // Without the option the terrain is an open grid with 4 * 256 border edges.
  const Scene open = load_ok(shared_scene("terragen/RealisticTerrain.ter"));
  EXPECT_EQ(open.meshes[0].kind, MeshKind::open);
  EXPECT_EQ(open.meshes[0].boundary_edges, 1024u);
  EXPECT_EQ(open.meshes[0].misoriented_edges, 0u);
}

// ---- assimp-testmodels ----

TEST(SceneLoaderAssimp, GltfBinaryAndTextBoxes) {
  for (const char* file :
       {"glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", "glTF2/BoxTextured-glTF/BoxTextured.gltf",
        "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf"}) {
    LoadStats stats;
    const Scene scene = load_ok(assimp_model(file), {}, &stats);
    expect_consistent(scene, stats);
    EXPECT_EQ(stats.triangles, 12u) << file;
    EXPECT_EQ(stats.closed_meshes, 1u) << file;  // 24 split vertices, welded to 8
    EXPECT_EQ(scene.vertices.size(), 8u) << file;
    expect_bounds_near(scene.bounds, {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}, 1e-6);
  }
}

TEST(SceneLoaderAssimp, ObjAndPlyCubesAreClosed) {
  for (const char* file : {"OBJ/box.obj", "PLY/cube.ply", "PLY/cube_binary.ply"}) {
    const Scene scene = load_ok(assimp_model(file));
    EXPECT_EQ(scene.triangle_count(), 12u) << file;  // 6 quads, triangulated
    ASSERT_EQ(scene.meshes.size(), 1u) << file;
    EXPECT_EQ(scene.meshes[0].kind, MeshKind::closed) << file;
    EXPECT_NEAR(scene.meshes[0].signed_volume, 1.0, 1e-6) << file;
  }
}

TEST(SceneLoaderAssimp, IfcLoads) {
  // Heavier than the rest (IFC geometry is built by assimp): only check it loads with its house.
  LoadStats stats;
  const Scene scene = load_ok(assimp_model("IFC/AC14-FZK-Haus.ifc"), {}, &stats);
  EXPECT_GT(stats.triangles, 10000u);
}

// ---- Node transforms ----

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint8_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= uint8_t(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= uint8_t(bytes[i + 2]);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[v & 63] : '=';
  }
  return out;
}

// A tetrahedron (outward winding) used by two nodes: "Far" at x = 10^7, and "Mirrored" (scale
// -1 in x) under "Parent" (translation y + 10, uniform scale 2).
std::filesystem::path write_transform_gltf(const std::filesystem::path& dir) {
  const float positions[12] = {0.3f, 0, 0, 1.3f, 0, 0, 0.3f, 1, 0, 0.3f, 0, 1};
  const uint16_t indices[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  std::string buffer(reinterpret_cast<const char*>(positions), sizeof positions);
  buffer.append(reinterpret_cast<const char*>(indices), sizeof indices);
  const std::string json = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 1]}],
  "nodes": [
    {"name": "Far", "mesh": 0, "translation": [10000000, 0, 0]},
    {"name": "Parent", "translation": [0, 10, 0], "scale": [2, 2, 2], "children": [2]},
    {"name": "Mirrored", "mesh": 0, "scale": [-1, 1, 1]}
  ],
  "meshes": [{"name": "tetra", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 72, "uri": "data:application/octet-stream;base64,)" +
                           base64(buffer) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0.3, 0, 0], "max": [1.3, 1, 1]},
    {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}
  ]
})";
  const auto path = dir / "transforms.gltf";
  write_file(path, json);
  return path;
}

TEST(SceneLoaderTransforms, NodeTranslationScaleAndMirrorAreApplied) {
  TempDir dir;
  LoadStats stats;
  const Scene scene = load_ok(write_transform_gltf(dir.path()), {}, &stats);
  expect_consistent(scene, stats);
  ASSERT_EQ(scene.meshes.size(), 2u);
  const MeshInfo* far = nullptr;
  const MeshInfo* mirrored = nullptr;
  for (const auto& m : scene.meshes) {
    if (m.name == "Far/tetra") far = &m;
    if (m.name == "Mirrored/tetra") mirrored = &m;
  }
  ASSERT_TRUE(far && mirrored) << scene.meshes[0].name << ", " << scene.meshes[1].name;

  // Composed in double: 0.3f + 10^7 keeps its fraction (float would round to 10000000).
  const double x0 = double(0.3f);
  expect_bounds_near(mesh_bounds(scene, *far), {1e7 + x0, 0, 0}, {1e7 + x0 + 1, 1, 1}, 1e-6);
  // Parent (T y+10, S 2) * Mirrored (S x-1): x -> -2x, y -> 2y + 10, z -> 2z.
  expect_bounds_near(mesh_bounds(scene, *mirrored), {-2 * (x0 + 1), 10, 0}, {-2 * x0, 12, 2}, 1e-6);
  // Both closed and outward facing: the mirror's winding was swapped.
  EXPECT_EQ(far->kind, MeshKind::closed);
  EXPECT_EQ(mirrored->kind, MeshKind::closed);
  EXPECT_NEAR(far->signed_volume, 1.0 / 6.0, 1e-6);
  EXPECT_NEAR(mirrored->signed_volume, 8.0 / 6.0, 1e-6);
  expect_bounds_near(scene.bounds, {-2 * (x0 + 1), 0, 0}, {1e7 + x0 + 1, 12, 2}, 1e-6);
}

// ---- Heightfield option ----

TEST(SceneLoaderHeightfield, MatchesNodeMeshOrFullName) {
  TempDir dir;
  const auto file = write_transform_gltf(dir.path());
  auto kinds = [&](std::vector<std::string> names) {
    const Scene scene = load_ok(file, {.heightfield_meshes = std::move(names)});
    std::string out;
    for (const auto& m : scene.meshes) out += m.name + "=" + mesh_kind_name(m.kind) + " ";
    return out;
  };
  EXPECT_EQ(kinds({}), "Far/tetra=closed Mirrored/tetra=closed ");
  EXPECT_EQ(kinds({"Far"}), "Far/tetra=heightfield Mirrored/tetra=closed ");
  EXPECT_EQ(kinds({"Mirrored/tetra"}), "Far/tetra=closed Mirrored/tetra=heightfield ");
  EXPECT_EQ(kinds({"tetra"}), "Far/tetra=heightfield Mirrored/tetra=heightfield ");
  EXPECT_EQ(kinds({"*"}), "Far/tetra=heightfield Mirrored/tetra=heightfield ");
}

TEST(SceneLoaderHeightfield, UnknownNameIsAnErrorListingTheMeshes) {
  TempDir dir;
  auto scene = load_scene(write_transform_gltf(dir.path()), {.heightfield_meshes = {"Far", "Terrain"}});
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error().code, ErrorCode::invalid_input);
  EXPECT_NE(scene.error().message.find("'Terrain'"), std::string::npos) << scene.error().message;
  EXPECT_NE(scene.error().message.find("Mirrored/tetra"), std::string::npos) << scene.error().message;
}

// ---- Errors and malformed input ----

TEST(SceneLoaderErrors, MissingFileIsNotFoundAndNamesTheFile) {
  auto scene = load_scene("/no/such/dir/scene.obj", {});
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error().code, ErrorCode::not_found);
  EXPECT_NE(scene.error().message.find("/no/such/dir/scene.obj"), std::string::npos);
}

TEST(SceneLoaderErrors, UnknownExtensionIsUnsupported) {
  TempDir dir;
  write_file(dir.path() / "scene.xyz", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  auto scene = load_scene(dir.path() / "scene.xyz", {});
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error().code, ErrorCode::unsupported);
  auto directory = load_scene(dir.path(), {});
  ASSERT_FALSE(directory.ok());
}

TEST(SceneLoaderErrors, AssimpInvalidModelsFailCleanly) {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(assimp_model("invalid"))) {
    const std::string name = entry.path().filename().string();
    if (name == "readme.txt") continue;
    ++files;
    auto scene = load_scene(entry.path(), {});
    if (name == "malformed2.obj") {  // only references a missing material: loads
      EXPECT_TRUE(scene.ok()) << name;
      continue;
    }
    ASSERT_FALSE(scene.ok()) << name;
    EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << name << ": " << scene.error().message;
    EXPECT_NE(scene.error().message.find(name), std::string::npos) << scene.error().message;
  }
  EXPECT_GE(files, 10);
}

TEST(SceneLoaderErrors, AssimpErrorMessageIsPassedOn) {
  auto scene = load_scene(assimp_model("invalid/malformed.obj"), {});
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().message.find("face index"), std::string::npos) << scene.error().message;
}

TEST(SceneLoaderErrors, HostileGltfFailsOrLoadsSanely) {
  // Recursive node graph, out-of-range indices, infinite positions, missing buffer file.
  for (const char* file :
       {"glTF2/RecursiveNodes/RecursiveNodes.gltf", "glTF2/IndexOutOfRange/IndexOutOfRange.gltf",
        "glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf",
        "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "glTF2/MissingBin/BoxTextured.gltf"}) {
    auto scene = load_scene(assimp_model(file), {});
    if (scene.ok()) {
      for (const auto& t : scene->triangles)
        for (uint32_t v : t) ASSERT_LT(v, scene->vertices.size()) << file;
    } else {
      EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << file;
    }
  }
  auto infinites = load_scene(assimp_model("glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb"), {});
  ASSERT_FALSE(infinites.ok());
  EXPECT_NE(infinites.error().message.find("no triangles"), std::string::npos) << infinites.error().message;
}

TEST(SceneLoaderErrors, TruncatedBinaryPly) {
  // Every length: cuts inside the header used to hang assimp 5.2's PLY parser forever.
  TempDir dir;
  const std::string full = read_file(assimp_model("PLY/cube_binary.ply"));
  ASSERT_GT(full.size(), 100u);
  const size_t header = full.find("end_header\n") + 11;
  for (size_t length = 0; length < full.size(); ++length) {
    const auto path = dir.path() / "truncated.ply";
    write_file(path, full.substr(0, length));
    auto scene = load_scene(path, {});
    if (scene.ok()) {  // a cut inside the face list may still give some faces; never more
      EXPECT_LE(scene->triangle_count(), 12u) << length;
      EXPECT_GE(length, header) << length;
    } else {
      EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << length;
    }
  }
  // A big binary PLY cut in half (inside the vertex list) is an error, not a crash.
  const std::string oahu = read_file(shared_scene("oahu/oahu_w158n21.ply"));
  write_file(dir.path() / "half.ply", oahu.substr(0, oahu.size() / 2));
  auto half = load_scene(dir.path() / "half.ply", {});
  if (half.ok()) {
    EXPECT_LT(half->triangle_count(), 488959u);
  } else {
    EXPECT_EQ(half.error().code, ErrorCode::invalid_input);
  }
}

// A small Terragen file: n x n samples, sample(x, y) = 100 * x - 7 * y, SCAL 2, height scale
// 65536 (1.0), base 5.
std::string make_ter(uint16_t n, bool finish = true) {
  std::string f = "TERRAGENTERRAIN ";
  auto i16 = [&](int16_t v) { f.append(reinterpret_cast<const char*>(&v), 2); };
  auto f32 = [&](float v) { f.append(reinterpret_cast<const char*>(&v), 4); };
  auto pad = [&] {
    while (f.size() % 4) f += '\0';
  };
  f += "SIZE";
  i16(int16_t(n - 1));
  pad();
  f += "XPTS";
  i16(int16_t(n));
  pad();
  f += "YPTS";
  i16(int16_t(n));
  pad();
  f += "SCAL";
  f32(2);
  f32(2);
  f32(2);
  f += "CRAD";
  f32(6370);
  f += "CRVM";
  f += '\0';
  pad();
  f += "ALTW";
  i16(0x7fff);
  i16(5);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) i16(int16_t(100 * x - 7 * y));
  if (!finish) return f;
  pad();
  f += "EOF ";
  return f;
}

TEST(SceneLoaderTerragen, SmallGridValues) {
  TempDir dir;
  write_file(dir.path() / "small.ter", make_ter(9));
  const Scene scene = load_ok(dir.path() / "small.ter");
  EXPECT_EQ(scene.triangle_count(), 8u * 8u * 2u);
  EXPECT_EQ(scene.vertices.size(), 81u);
  // z = SCAL.z * (base + sample * 32767 / 65536).
  const double k = 32767.0 / 65536.0;
  expect_bounds_near(scene.bounds, {0, 0, 2 * (5 - 56 * k)}, {16, 16, 2 * (5 + 800 * k)}, 1e-9);
  for (const Vec3& p : scene.vertices) {
    const double x = p[0] / 2, y = p[1] / 2;
    EXPECT_NEAR(p[2], 2 * (5 + (100 * x - 7 * y) * k), 1e-9);
  }
}

TEST(SceneLoaderTerragen, EveryTruncationAndByteFlipIsSafe) {
  // Our own reader: every cut and every byte flipped, on a small grid (fast under ASan).
  TempDir dir;
  const std::string full = make_ter(5);
  const auto path = dir.path() / "t.ter";
  const size_t samples_end = make_ter(5, /*finish=*/false).size();
  for (size_t n = 0; n < full.size(); ++n) {
    write_file(path, full.substr(0, n));
    auto scene = load_scene(path, {});
    if (n < samples_end) {  // any cut before the last sample is an error
      ASSERT_FALSE(scene.ok()) << n;
      EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << n;
    } else {  // only padding or the EOF marker missing: tolerated
      ASSERT_TRUE(scene.ok()) << n;
      EXPECT_EQ(scene->triangle_count(), 32u);
    }
  }
  for (size_t at = 0; at < full.size(); ++at)
    for (uint8_t mask : {uint8_t(0xff), uint8_t(0x01), uint8_t(0x80)}) {
      std::string corrupt = full;
      corrupt[at] = char(corrupt[at] ^ mask);
      write_file(path, corrupt);
      auto scene = load_scene(path, {});
      if (scene.ok()) {
        EXPECT_LE(scene->triangle_count(), 65535u * 65535u * 2u) << at;
        for (const Vec3& p : scene->vertices) ASSERT_TRUE(std::isfinite(p[2])) << at;
      }
    }
  // The real file cut inside its samples.
  const std::string real = read_file(shared_scene("terragen/RealisticTerrain.ter"));
  write_file(path, real.substr(0, real.size() / 2));
  auto half = load_scene(path, {});
  ASSERT_FALSE(half.ok());
  EXPECT_NE(half.error().message.find("samples"), std::string::npos) << half.error().message;
}

TEST(SceneLoaderErrors, GarbageObj) {
  TempDir dir;
  std::string garbage = "this is not a mesh\n\x01\x02\x03 at all {}[]\nf 1 2 x\n";
  for (int i = 0; i < 50; ++i) garbage += "random words " + std::to_string(i * 7919) + " %%% \n";
  write_file(dir.path() / "garbage.obj", garbage);
  auto scene = load_scene(dir.path() / "garbage.obj", {});
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error().code, ErrorCode::invalid_input);
}

TEST(SceneLoaderErrors, NonFiniteObjVerticesAreDroppedAndCounted) {
  TempDir dir;
  write_file(dir.path() / "nan.obj",
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv nan 0 0\nv 0 inf 0\n"
             "f 1 2 3\nf 2 4 3\nf 1 2 5\nf 1 6 2\nf 5 6 4\n");
  LoadStats stats;
  const Scene scene = load_ok(dir.path() / "nan.obj", {}, &stats);
  EXPECT_EQ(stats.triangles, 2u);
  EXPECT_EQ(stats.dropped_triangles, 3u);
  expect_bounds_near(scene.bounds, {0, 0, 0}, {1, 1, 0}, 0);  // the bad vertices never reach the bounds
}

TEST(SceneLoaderErrors, OnlyPointsAndLinesIsNoTriangles) {
  TempDir dir;
  write_file(dir.path() / "lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\np 2\nl 1 2\nl 2 3 1\n");
  write_file(dir.path() / "cloud.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  write_file(dir.path() / "degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  for (const char* name : {"lines.obj", "cloud.obj", "degenerate.obj"}) {
    auto scene = load_scene(dir.path() / name, {});
    ASSERT_FALSE(scene.ok()) << name;
    EXPECT_EQ(scene.error().code, ErrorCode::invalid_input) << name;
    EXPECT_NE(scene.error().message.find("no triangles"), std::string::npos) << scene.error().message;
  }
  for (const char* model : {"OBJ/testpoints.obj", "OBJ/testline.obj", "PLY/points.ply"}) {
    auto scene = load_scene(assimp_model(model), {});
    ASSERT_FALSE(scene.ok()) << model;
    EXPECT_NE(scene.error().message.find("no triangles"), std::string::npos) << scene.error().message;
  }
}

TEST(SceneLoaderErrors, MixedPrimitivesKeepOnlyTriangles) {
  TempDir dir;
  write_file(dir.path() / "mixed.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\np 1\nl 1 4\nf 1 2 4 3\n");
  const Scene scene = load_ok(dir.path() / "mixed.obj");
  EXPECT_EQ(scene.triangle_count(), 2u);  // the quad, triangulated
}

}  // namespace
}  // namespace shadowtiles
