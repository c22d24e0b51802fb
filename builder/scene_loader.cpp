#include "builder/scene_loader.hpp"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <new>
#include <unordered_map>
#include <unordered_set>

#include "builder/mesh_file_prechecks.hpp"
#include "builder/ply_triangle_reader.hpp"

namespace shadowtiles {
namespace {

// assimp's log -> spdlog debug (assimp warnings about a file are useful when a load looks wrong, but
// too chatty for info).
class SpdlogStream : public Assimp::LogStream {
 public:
  void write(const char* message) override {
    std::string_view text(message);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.remove_suffix(1);
    spdlog::debug("assimp: {}", text);
  }
};

void install_assimp_logger() {
  static std::once_flag once;
  std::call_once(once, [] {
    // No log file, no default streams; severities up to warnings and errors (NORMAL drops the very
    // verbose per-step debug output).
    Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
    Assimp::DefaultLogger::get()->attachStream(
        new SpdlogStream, Assimp::Logger::Info | Assimp::Logger::Warn | Assimp::Logger::Err);
  });
}

// Row-major 4x4 affine transform in double (assimp's aiMatrix4x4 is float).
using Matrix = std::array<std::array<double, 4>, 4>;

Matrix to_matrix(const aiMatrix4x4& a) {
  const ai_real* rows[4] = {&a.a1, &a.b1, &a.c1, &a.d1};
  Matrix m{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m[i][j] = double(rows[i][j]);
  return m;
}

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix m{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) m[i][j] += a[i][k] * b[k][j];
  return m;
}

double determinant3(const Matrix& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Vec3 transform(const Matrix& m, const aiVector3D& v) {
  const double x = v.x, y = v.y, z = v.z;
  return {m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3],
          m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3],
          m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3]};
}

std::string instance_name(const std::string& node, const std::string& mesh, const std::string& file_stem) {
  if (node.empty() && mesh.empty()) return file_stem;  // PLY, STL: no names at all
  if (mesh.empty() || node == mesh) return node;
  if (node.empty()) return mesh;
  return node + "/" + mesh;
}

std::string format_bounds(const WorldBounds& b) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}] .. [{:.6g}, {:.6g}, {:.6g}]", b.min[0], b.min[1], b.min[2],
                     b.max[0], b.max[1], b.max[2]);
}

// Applies LoadOptions::heightfield_meshes and remembers which entries matched something.
class HeightfieldMatcher {
 public:
  explicit HeightfieldMatcher(const std::vector<std::string>& patterns)
      : patterns_(patterns), used_(patterns.size(), false) {}

  bool match(const std::string& full, const std::string& node, const std::string& mesh) {
    bool any = false;
    for (size_t p = 0; p < patterns_.size(); ++p)
      if (patterns_[p] == "*" || patterns_[p] == full || (!node.empty() && patterns_[p] == node) ||
          (!mesh.empty() && patterns_[p] == mesh)) {
        used_[p] = true;
        any = true;
      }
    return any;
  }

  // A name that matches nothing is almost certainly a typo: fail rather than silently build a
  // terrain without its solid-below rule.
  Status check_all_used(const Scene& scene, const std::filesystem::path& file) const {
    for (size_t p = 0; p < patterns_.size(); ++p) {
      if (used_[p]) continue;
      std::string names;
      for (size_t m = 0; m < scene.meshes.size() && m < 20; ++m)
        names += (m ? ", " : "") + scene.meshes[m].name;
      if (scene.meshes.size() > 20) names += fmt::format(", ... ({} meshes)", scene.meshes.size());
      return make_error(ErrorCode::invalid_input,
                        fmt::format("{}: heightfield mesh '{}' matches no mesh; meshes: {}", file.string(),
                                    patterns_[p], names.empty() ? "(none)" : names));
    }
    return Status::success();
  }

 private:
  const std::vector<std::string>& patterns_;
  std::vector<bool> used_;
};

Error too_big(const std::filesystem::path& file) {
  return make_error(ErrorCode::invalid_input,
                    fmt::format("{}: more than 2^32 - 1 triangles or vertices", file.string()));
}

// Walks assimp's node tree (iteratively: a hostile file can nest deeply) and adds every mesh instance.
Result<Scene> convert(const aiScene& ai, const std::filesystem::path& file, HeightfieldMatcher& matcher) {
  Scene scene;
  std::unordered_map<std::string, int> name_count;
  std::vector<Vec3> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
  const std::string stem = file.stem().string();

  struct Item {
    const aiNode* node;
    Matrix world;
    unsigned depth;
  };
  constexpr unsigned kMaxDepth = 10000;
  std::vector<Item> stack;
  std::unordered_set<const aiNode*> visited;  // a malformed graph must not loop
  if (ai.mRootNode) stack.push_back({ai.mRootNode, to_matrix(ai.mRootNode->mTransformation), 0});
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    const aiNode& node = *item.node;
    if (!visited.insert(item.node).second) continue;
    const std::string node_name(node.mName.C_Str());
    const bool mirrored = determinant3(item.world) < 0;

    for (unsigned i = 0; i < node.mNumMeshes && node.mMeshes; ++i) {
      const unsigned mesh_index = node.mMeshes[i];
      if (mesh_index >= ai.mNumMeshes || !ai.mMeshes || !ai.mMeshes[mesh_index]) continue;
      const aiMesh& mesh = *ai.mMeshes[mesh_index];
      if (!(mesh.mPrimitiveTypes & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON)) || !mesh.mVertices ||
          !mesh.mFaces)
        continue;  // points and lines only
      vertices.clear();
      triangles.clear();
      vertices.reserve(mesh.mNumVertices);
      for (unsigned v = 0; v < mesh.mNumVertices; ++v)
        vertices.push_back(transform(item.world, mesh.mVertices[v]));
      uint64_t polygons = 0;  // left after aiProcess_Triangulate: should not happen; counted as dropped
      triangles.reserve(mesh.mNumFaces);
      for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices < 3 || !face.mIndices) continue;  // points, lines
        if (face.mNumIndices > 3) {
          ++polygons;
          continue;
        }
        const uint32_t a = face.mIndices[0], b = face.mIndices[1], c = face.mIndices[2];
        triangles.push_back(mirrored ? std::array<uint32_t, 3>{a, c, b} : std::array<uint32_t, 3>{a, b, c});
      }
      if (triangles.empty() && polygons == 0) continue;

      constexpr uint64_t kLimit = 0xffffffffull;  // Scene indexes with uint32
      if (scene.triangles.size() + uint64_t(triangles.size()) > kLimit ||
          scene.vertices.size() + uint64_t(vertices.size()) > kLimit)
        return too_big(file);
      const std::string mesh_name(mesh.mName.C_Str());
      std::string name = instance_name(node_name, mesh_name, stem);
      // fmt, not string operator+: GCC 12 reports a false -Wrestrict on the latter here.
      if (const int n = ++name_count[name]; n > 1) name += fmt::format("#{}", n);
      (void)scene.add_mesh(name, vertices, triangles, matcher.match(name, node_name, mesh_name));
      scene.meshes.back().dropped_triangles += polygons;
    }
    if (item.depth >= kMaxDepth) {
      if (node.mNumChildren > 0)
        return make_error(ErrorCode::invalid_input,
                          fmt::format("{}: node hierarchy deeper than {}", file.string(), kMaxDepth));
      continue;
    }
    for (unsigned c = node.mNumChildren; c-- > 0;)  // reversed: children pop in file order
      if (node.mChildren && node.mChildren[c])
        stack.push_back({node.mChildren[c],
                         multiply(item.world, to_matrix(node.mChildren[c]->mTransformation)),
                         item.depth + 1});
  }
  return scene;
}

// A PLY triangle mesh read without assimp, as convert() turns assimp's scene of it into a Scene: one
// mesh, no node or mesh names (the mesh is named after the file), the identity transform applied
// through the same arithmetic, so the two paths give the same scene bit for bit.
Result<Scene> scene_from_ply_mesh(PlyTriangleMesh mesh, const std::filesystem::path& file,
                                  HeightfieldMatcher& matcher) {
  Scene scene;
  Matrix identity{};
  for (int i = 0; i < 4; ++i) identity[i][i] = 1;
  std::vector<Vec3> vertices;
  vertices.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) vertices.push_back(transform(identity, aiVector3D(v[0], v[1], v[2])));
  mesh.vertices = {};
  const std::string name = instance_name("", "", file.stem().string());
  (void)scene.add_mesh(name, vertices, mesh.triangles, matcher.match(name, "", ""));
  return scene;
}

Result<Scene> import_with_assimp(const std::filesystem::path& file, const std::string& extension,
                                 HeightfieldMatcher& matcher) {
  // The PLY/OFF pre-checks first: they are one read of the file, while constructing an
  // Importer registers every importer and post-processing step (most of a refused file's cost).
  if (extension == ".ply" || extension == ".off") {
    std::error_code ec;
    const uint64_t file_size = std::filesystem::file_size(file, ec);
    if (ec) return make_error(ErrorCode::io_error, fmt::format("{}: {}", file.string(), ec.message()));
    if (Status ok = extension == ".ply" ? check_ply_file(file, file_size) : check_off_file(file, file_size); !ok)
      return ok.error();
    if (extension == ".ply") {  // the common binary triangle layout, without assimp's document of it
      try {
        auto mesh = read_ply_triangles(file, file_size);
        if (!mesh) return mesh.error();
        if (*mesh) return scene_from_ply_mesh(std::move(**mesh), file, matcher);
      } catch (const std::bad_alloc&) {
        return make_error(ErrorCode::invalid_input, fmt::format("{}: out of memory", file.string()));
      }
    }
  }

  install_assimp_logger();
  Assimp::Importer importer;
  if (extension.empty() || !importer.IsExtensionSupported(extension)) {
    std::string list;
    importer.GetExtensionList(list);
    return make_error(
        ErrorCode::unsupported,
        fmt::format("{}: no importer for the extension '{}' (known: {})", file.string(), extension, list));
  }

  // Skeleton placeholder meshes some importers invent are not geometry.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  auto assimp_error = [&] {
    std::string message = importer.GetErrorString();
    while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
    return make_error(ErrorCode::invalid_input,
                      fmt::format("{}: {}", file.string(), message.empty() ? "import failed" : message));
  };
  const aiScene* ai = nullptr;
  try {
    // Two steps: read raw, then validate + triangulate. Validation rejects meshes without faces (point
    // clouds), which deserve the clearer "no triangles"; so look for a polygon first (defensively:
    // the structure is not validated yet).
    // No JoinIdenticalVertices: Scene::add_mesh welds by position, cheaper than assimp's
    // all-attribute comparison.
    ai = importer.ReadFile(file.string(), 0);
    if (!ai) return assimp_error();
    bool any_polygon = false;
    for (unsigned m = 0; m < ai->mNumMeshes && ai->mMeshes && !any_polygon; ++m) {
      const aiMesh* mesh = ai->mMeshes[m];
      for (unsigned f = 0; mesh && mesh->mFaces && f < mesh->mNumFaces && !any_polygon; ++f)
        any_polygon = mesh->mFaces[f].mNumIndices >= 3;
    }
    if (!any_polygon)
      return make_error(ErrorCode::invalid_input,
                        fmt::format("{}: no triangles (only points or lines)", file.string()));
    // Validation first (assimp runs it before the other steps): bad indices, null arrays.
    ai = importer.ApplyPostProcessing(aiProcess_ValidateDataStructure | aiProcess_Triangulate);
  } catch (const std::bad_alloc&) {
    return make_error(ErrorCode::invalid_input,
                      fmt::format("{}: out of memory while importing", file.string()));
  } catch (const std::exception& e) {
    return make_error(ErrorCode::invalid_input, fmt::format("{}: {}", file.string(), e.what()));
  } catch (...) {
    return make_error(ErrorCode::invalid_input, fmt::format("{}: import failed", file.string()));
  }
  if (!ai) return assimp_error();
  try {
    return convert(*ai, file, matcher);
  } catch (const std::bad_alloc&) {
    return make_error(ErrorCode::invalid_input, fmt::format("{}: out of memory", file.string()));
  }
}

// Terragen .ter, read here because assimp 5.2's reader is broken (assimp issues #3093, #4931: it
// mis-skips chunk padding and fails with "End of file or read limit was reached"; fixed after 5.2.5).
// Format: "TERRAGEN" "TERRAIN " then 4-byte-aligned chunks: SIZE (int16: side - 1), XPTS, YPTS
// (int16), SCAL (3 float32: metres per unit in x, y, z), CRAD (float32), CRVM (uint8: 0 = flat),
// ALTW (int16 height scale, int16 base height, then XPTS * YPTS int16 samples, rows south to north,
// west to east), EOF. Height in metres = SCAL.z * (base + sample * scale / 65536).
// Output: z up, x east, y north, metres, origin at the south-west sample; two triangles per cell,
// split along the south-west/north-east diagonal, counter-clockwise seen from above.
Result<Scene> read_terragen(const std::filesystem::path& file, HeightfieldMatcher& matcher) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return make_error(ErrorCode::io_error, fmt::format("{}: cannot open", file.string()));
  const std::vector<char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto fail = [&](const std::string& why) {
    return make_error(ErrorCode::invalid_input, fmt::format("{}: Terragen: {}", file.string(), why));
  };
  size_t pos = 0;
  auto has = [&](size_t n) { return pos <= data.size() && data.size() - pos >= n; };
  auto i16 = [&] {
    int16_t v;
    std::memcpy(&v, data.data() + pos, 2);
    pos += 2;
    return v;
  };
  auto f32 = [&] {
    float v;
    std::memcpy(&v, data.data() + pos, 4);
    pos += 4;
    return v;
  };
  if (data.size() < 16 || std::memcmp(data.data(), "TERRAGENTERRAIN ", 16) != 0)
    return fail("missing the TERRAGEN TERRAIN magic");
  pos = 16;
  uint32_t nx = 0, ny = 0;
  double scale[3] = {30, 30, 30};  // Terragen's default: 30 m per unit
  double height_scale = 0, base_height = 0;
  size_t samples = 0;  // offset of the ALTW samples, 0 = not seen
  while (has(4)) {
    const std::string chunk(data.data() + pos, 4);
    pos += 4;
    if (chunk == "EOF ") break;
    if (chunk == "SIZE" || chunk == "XPTS" || chunk == "YPTS") {
      if (!has(2)) return fail("truncated " + chunk);
      const uint32_t v = uint16_t(i16());
      if (chunk == "SIZE")
        nx = ny = v + 1;
      else
        (chunk == "XPTS" ? nx : ny) = v;
    } else if (chunk == "SCAL") {
      if (!has(12)) return fail("truncated SCAL");
      for (double& s : scale) s = f32();
    } else if (chunk == "CRAD") {
      if (!has(4)) return fail("truncated CRAD");
      pos += 4;
    } else if (chunk == "CRVM") {
      if (!has(1)) return fail("truncated CRVM");
      if (data[pos] != 0)
        spdlog::warn("{}: Terragen spherical mapping ignored; loading the terrain flat", file.string());
      pos += 1;
    } else if (chunk == "ALTW") {
      if (!has(4)) return fail("truncated ALTW");
      height_scale = i16() / 65536.0;
      base_height = i16();
      if (nx < 2 || ny < 2) return fail(fmt::format("invalid terrain size {} x {}", nx, ny));
      if (!has(size_t(nx) * ny * 2))
        return fail(fmt::format("ALTW holds fewer than {} x {} samples", nx, ny));
      samples = pos;
      pos += size_t(nx) * ny * 2;
    } else {
      return fail(fmt::format("unknown chunk at byte {}", pos - 4));
    }
    pos = (pos + 3) & ~size_t(3);  // chunks are 4-byte aligned
  }
  if (samples == 0) return fail("no ALTW (height data) chunk");
  for (double s : scale)
    if (!std::isfinite(s) || s == 0) return fail("invalid SCAL");

  if (uint64_t(nx - 1) * (ny - 1) * 2 > 0xffffffffull) return too_big(file);
  std::vector<Vec3> vertices;
  vertices.reserve(size_t(nx) * ny);
  pos = samples;
  for (uint32_t y = 0; y < ny; ++y)
    for (uint32_t x = 0; x < nx; ++x)
      vertices.push_back({x * scale[0], y * scale[1], scale[2] * (base_height + i16() * height_scale)});
  std::vector<std::array<uint32_t, 3>> triangles;
  triangles.reserve(size_t(nx - 1) * (ny - 1) * 2);
  for (uint32_t y = 0; y + 1 < ny; ++y)
    for (uint32_t x = 0; x + 1 < nx; ++x) {
      const uint32_t sw = y * nx + x, se = sw + 1, nw = sw + nx, ne = nw + 1;
      triangles.push_back({sw, se, ne});
      triangles.push_back({sw, ne, nw});
    }
  Scene scene;
  const std::string name = file.stem().string();
  (void)scene.add_mesh(name, vertices, triangles, matcher.match(name, "", name));
  return scene;
}

}  // namespace

Result<Scene> load_scene(const std::filesystem::path& file, const LoadOptions& options, LoadStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    return make_error(ErrorCode::not_found, fmt::format("scene file not found: {}", file.string()));
  if (std::filesystem::is_directory(file, ec))
    return make_error(ErrorCode::invalid_input, fmt::format("scene file is a directory: {}", file.string()));

  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  HeightfieldMatcher matcher(options.heightfield_meshes);
  Result<Scene> loaded =
      extension == ".ter" ? read_terragen(file, matcher) : import_with_assimp(file, extension, matcher);
  if (!loaded) return loaded;
  Scene& scene = loaded.value();
  if (scene.triangles.empty()) {
    uint64_t dropped = 0;
    for (const MeshInfo& m : scene.meshes) dropped += m.dropped_triangles;
    return make_error(
        ErrorCode::invalid_input,
        fmt::format("{}: no triangles ({} meshes, {} triangles dropped as degenerate or malformed)",
                    file.string(), scene.meshes.size(), dropped));
  }
  if (Status status = matcher.check_all_used(scene, file); !status) return status.error();

  LoadStats s;
  s.triangles = scene.triangle_count();
  s.meshes = scene.meshes.size();
  uint64_t boundary = 0, non_manifold = 0, misoriented = 0, inside_out = 0;
  for (const MeshInfo& m : scene.meshes) {
    s.dropped_triangles += m.dropped_triangles;
    switch (m.kind) {
      case MeshKind::closed:
        ++s.closed_meshes;
        break;
      case MeshKind::open:
        ++s.open_meshes;
        break;
      case MeshKind::heightfield:
        ++s.heightfield_meshes;
        break;
    }
    boundary += m.boundary_edges;
    non_manifold += m.non_manifold_edges;
    misoriented += m.misoriented_edges;
    if (m.kind == MeshKind::closed && m.signed_volume < 0) ++inside_out;
    spdlog::debug(
        "  mesh '{}': {} triangles, {} dropped, {} (boundary {}, non-manifold {}, misoriented {}){}", m.name,
        m.triangle_count, m.dropped_triangles, mesh_kind_name(m.kind), m.boundary_edges, m.non_manifold_edges,
        m.misoriented_edges, m.kind == MeshKind::closed && m.signed_volume < 0 ? ", inside out" : "");
  }
  if (options.close_nearly_closed) {
    s.nearly_closed = close_nearly_closed_meshes(scene, options.nearly_closed);
    s.closed_meshes += s.nearly_closed.accepted_meshes;
    s.open_meshes -= s.nearly_closed.accepted_meshes;
  }
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  spdlog::info("loaded {}: {} triangles ({} dropped), {} meshes, bounds {}, {} up, {:.2f} s", file.string(),
               s.triangles, s.dropped_triangles, s.meshes, format_bounds(scene.bounds),
               options.up == UpAxis::z ? "z" : "y", s.seconds);
  spdlog::info(
      "  meshes: {} closed{}, {} open (edges: {} boundary, {} non-manifold, {} misoriented), "
      "{} heightfield",
      s.closed_meshes, inside_out ? fmt::format(" ({} inside out)", inside_out) : "", s.open_meshes, boundary,
      non_manifold, misoriented, s.heightfield_meshes);
  if (stats) *stats = s;
  return loaded;
}

}  // namespace shadowtiles
