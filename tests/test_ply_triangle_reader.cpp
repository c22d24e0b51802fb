// The binary PLY triangle reader (builder/ply_triangle_reader.hpp): the scene it gives equals assimp's
// for the same mesh (the shared scenes' PLYs, checked against their big-endian twins, which assimp
// reads), and files outside its layout go to assimp as before.
#include "builder/ply_triangle_reader.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "builder/mesh_file_prechecks.hpp"
#include "builder/scene_loader.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using testing::assimp_model;
using testing::read_file;
using testing::shared_scene;
using testing::TempDir;
using testing::write_file;

// A little-endian "vertex: float x, y, z; face: list uchar int" file rewritten big-endian: the same
// mesh, which the reader leaves to assimp.
std::string big_endian_twin(const std::string& file) {
  const size_t body = file.find("end_header\n") + 11;
  std::string header = file.substr(0, body);
  const size_t format = header.find("binary_little_endian");
  header.replace(format, 20, "binary_big_endian");
  const auto count = [&](const char* element) {
    const size_t at = header.find(std::string("element ") + element + " ");
    return std::stoull(header.substr(at + std::strlen(element) + 9));
  };
  const uint64_t vertices = count("vertex"), faces = count("face");
  std::string out = header;
  size_t pos = body;
  auto swap4 = [&] {
    for (int k = 3; k >= 0; --k) out += file[pos + size_t(k)];
    pos += 4;
  };
  for (uint64_t v = 0; v < 3 * vertices; ++v) swap4();
  for (uint64_t f = 0; f < faces; ++f) {
    const unsigned n = static_cast<unsigned char>(file[pos]);
    out += file[pos++];
    for (unsigned k = 0; k < n; ++k) swap4();
  }
  return out;
}

void expect_same_scene(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t i = 0; i < a.vertices.size(); ++i)
    ASSERT_EQ(std::memcmp(&a.vertices[i], &b.vertices[i], sizeof(Vec3)), 0) << "vertex " << i;
  ASSERT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(a.triangle_mesh, b.triangle_mesh);
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    EXPECT_EQ(a.meshes[m].name, b.meshes[m].name);
    EXPECT_EQ(a.meshes[m].kind, b.meshes[m].kind);
    EXPECT_EQ(a.meshes[m].dropped_triangles, b.meshes[m].dropped_triangles);
    EXPECT_EQ(a.meshes[m].boundary_edges, b.meshes[m].boundary_edges);
  }
}

Scene load_ok(const std::filesystem::path& file, const LoadOptions& options = {}) {
  auto scene = load_scene(file, options);
  EXPECT_TRUE(scene.ok()) << file << ": " << (scene.ok() ? "" : scene.error().message);
  return scene.ok() ? std::move(scene).value() : Scene{};
}

TEST(PlyTriangleReader, SameSceneAsAssimp) {
  TempDir dir;
  for (const auto& [file, heightfield] :
       {std::pair{shared_scene("oahu/oahu_w158n21.ply"), true},
        std::pair{shared_scene("honolulu_airport/honolulu_airport_harbour.ply"), false},
        std::pair{shared_scene("terragen/RealisticTerrain.ply"), true},
        std::pair{assimp_model("PLY/cube_binary.ply"), false}}) {
    SCOPED_TRACE(file.string());
    const std::string bytes = read_file(file);
    auto mesh = read_ply_triangles(file, bytes.size());
    ASSERT_TRUE(mesh.ok());
    ASSERT_TRUE(mesh->has_value()) << "not read by the reader";
    // Named like the original, so the mesh names (the file's stem) agree.
    const auto twin = dir.path() / "big" / file.filename();
    std::filesystem::create_directories(twin.parent_path());
    write_file(twin, big_endian_twin(bytes));
    auto twin_mesh = read_ply_triangles(twin, std::filesystem::file_size(twin));
    ASSERT_TRUE(twin_mesh.ok());
    EXPECT_FALSE(twin_mesh->has_value()) << "big-endian: assimp's";
    LoadOptions options;
    if (heightfield) options.heightfield_meshes = {"*"};
    expect_same_scene(load_ok(file, options), load_ok(twin, options));
  }
}

// A header with the vertex's coordinates among other properties, in another order.
std::string interleaved_ply(const std::string& face_list) {
  std::string f =
      "ply\nformat binary_little_endian 1.0\ncomment made by a test\nelement vertex 4\nproperty uchar red\n"
      "property float z\nproperty double w\nproperty float x\nproperty float y\nelement face 2\n" +
      face_list + "\nend_header\n";
  const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}};
  for (const auto& p : xyz) {
    f += char(7);
    f.append(reinterpret_cast<const char*>(&p[2]), 4);
    const double w = 9;
    f.append(reinterpret_cast<const char*>(&w), 8);
    f.append(reinterpret_cast<const char*>(&p[0]), 4);
    f.append(reinterpret_cast<const char*>(&p[1]), 4);
  }
  return f;
}

void append_face(std::string& f, std::initializer_list<int32_t> indices) {
  f += char(indices.size());
  for (int32_t i : indices) f.append(reinterpret_cast<const char*>(&i), 4);
}

TEST(PlyTriangleReader, ReadsCoordinatesAmongOtherProperties) {
  TempDir dir;
  std::string f = interleaved_ply("property list uchar int vertex_indices");
  append_face(f, {0, 1, 2});
  append_face(f, {0, 2, 3});
  const auto path = dir.path() / "interleaved.ply";
  write_file(path, f);
  ASSERT_TRUE(check_ply_file(path, f.size()).ok());
  auto mesh = read_ply_triangles(path, f.size());
  ASSERT_TRUE(mesh.ok());
  ASSERT_TRUE(mesh->has_value());
  const PlyTriangleMesh& m = **mesh;
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.vertices[2], (std::array<float, 3>{1, 1, 0}));
  EXPECT_EQ(m.vertices[3], (std::array<float, 3>{0, 1, 0.5f}));
  EXPECT_EQ(m.triangles, (std::vector<std::array<uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}}));
}

TEST(PlyTriangleReader, LeavesOtherLayoutsToAssimp) {
  TempDir dir;
  auto not_read = [&](const std::string& name, const std::string& f) {
    const auto path = dir.path() / name;
    write_file(path, f);
    auto mesh = read_ply_triangles(path, f.size());
    ASSERT_TRUE(mesh.ok()) << name;
    EXPECT_FALSE(mesh->has_value()) << name;
  };
  // A quad: assimp triangulates it, so the file still loads, as two triangles.
  std::string quad = interleaved_ply("property list uchar int vertex_indices");
  append_face(quad, {0, 1, 2, 3});
  append_face(quad, {0, 2, 3});
  not_read("quad.ply", quad);
  auto scene = load_scene(dir.path() / "quad.ply", {});
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  EXPECT_EQ(scene->triangle_count(), 3u);
  // An index past the vertices, and a negative one: assimp's errors, as before this reader.
  for (int32_t bad : {4, -1}) {
    std::string f = interleaved_ply("property list uchar int vertex_indices");
    append_face(f, {0, 1, 2});
    append_face(f, {0, bad, 3});
    not_read("bad_index.ply", f);
  }
  // Another element, a face property besides the list, 2-byte indices, double coordinates.
  std::string extra_element = interleaved_ply("property list uchar int vertex_indices");
  extra_element.insert(extra_element.find("end_header"), "element edge 0\nproperty int vertex1\n");
  append_face(extra_element, {0, 1, 2});
  append_face(extra_element, {0, 2, 3});
  not_read("edge.ply", extra_element);
  std::string face_colour = interleaved_ply("property list uchar int vertex_indices\nproperty uchar red");
  not_read("colour.ply", face_colour);
  std::string short_indices = interleaved_ply("property list uchar short vertex_indices");
  not_read("short.ply", short_indices);
  std::string doubles = interleaved_ply("property list uchar int vertex_indices");
  doubles.replace(doubles.find("float x"), 7, "double x");
  not_read("double.ply", doubles);
  // Header lines assimp reads otherwise: the format after a comment, a comment inside an element's
  // properties (assimp drops the properties after it), a \r inside a line.
  std::string late_format = interleaved_ply("property list uchar int vertex_indices");
  late_format.insert(late_format.find("format"), "comment first\n");
  not_read("late_format.ply", late_format);
  std::string inner_comment = interleaved_ply("property list uchar int vertex_indices");
  inner_comment.insert(inner_comment.find("property float x"), "comment here\n");
  not_read("inner_comment.ply", inner_comment);
  std::string inner_cr = interleaved_ply("property list uchar int vertex_indices");
  inner_cr.replace(inner_cr.find("comment made by a test"), 22, "comment made\rby a test");
  not_read("inner_cr.ply", inner_cr);
}

}  // namespace
}  // namespace shadowtiles
