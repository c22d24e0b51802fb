#include "builder/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "builder/mesh_classifier.hpp"

namespace shadowtiles {
namespace {

// Height below this fraction of the longest edge counts as zero area (see Scene::add_mesh).
constexpr double kRelativeAreaEpsilon = 1e-10;

bool finite(const Vec3& p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

bool zero_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const Vec3 ac{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const Vec3 bc{c[0] - b[0], c[1] - b[1], c[2] - b[2]};
  const Vec3 n{ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
  auto length2 = [](const Vec3& v) { return v[0] * v[0] + v[1] * v[1] + v[2] * v[2]; };
  const double longest2 = std::max({length2(ab), length2(ac), length2(bc)});
  // !(x > y) rather than x <= y so a NaN from overflow counts as degenerate too.
  return !(std::sqrt(length2(n)) > kRelativeAreaEpsilon * longest2);
}

// Room for `extra` more elements, growing geometrically: a scene of many meshes appends one at a
// time, and exact reserves would copy the whole array per mesh.
template <typename T>
void reserve_more(std::vector<T>& v, size_t extra) {
  if (v.capacity() - v.size() < extra) v.reserve(std::max(v.size() + extra, 2 * v.capacity()));
}

}  // namespace

const char* mesh_kind_name(MeshKind kind) {
  switch (kind) {
    case MeshKind::open:
      return "open";
    case MeshKind::closed:
      return "closed";
    case MeshKind::heightfield:
      return "heightfield";
  }
  return "unknown";
}

uint64_t Scene::add_mesh(const std::string& name, const std::vector<Vec3>& mesh_vertices,
                         const std::vector<std::array<uint32_t, 3>>& mesh_triangles, bool heightfield) {
  MeshInfo info;
  info.name = name;
  info.first_triangle = uint32_t(std::min<size_t>(triangles.size(), std::numeric_limits<uint32_t>::max()));
  info.kind = heightfield ? MeshKind::heightfield : MeshKind::open;

  // 1. Filter triangles; collect the vertices they use.
  const size_t n = mesh_vertices.size();
  std::vector<std::array<uint32_t, 3>> kept;
  kept.reserve(mesh_triangles.size());
  std::vector<uint8_t> used(n, 0);
  for (const auto& t : mesh_triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    const Vec3 &a = mesh_vertices[t[0]], &b = mesh_vertices[t[1]], &c = mesh_vertices[t[2]];
    if (!finite(a) || !finite(b) || !finite(c) || zero_area(a, b, c)) continue;
    kept.push_back(t);
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
  }

  // 2. Weld the used vertices by position; dense ids follow first occurrence, so they can be appended
  //    in order.
  std::vector<uint32_t> used_index;  // dense used position -> mesh vertex
  std::vector<Vec3> used_positions;
  used_index.reserve(n);
  used_positions.reserve(n);
  std::vector<uint32_t> compact(n, 0);
  for (size_t i = 0; i < n; ++i)
    if (used[i]) {
      compact[i] = uint32_t(used_index.size());
      used_index.push_back(uint32_t(i));
      used_positions.push_back(mesh_vertices[i]);
    }
  uint32_t unique = 0;
  const std::vector<uint32_t> weld = weld_positions(used_positions, &unique);

  constexpr uint64_t kLimit = std::numeric_limits<uint32_t>::max();
  if (uint64_t(vertices.size()) + unique > kLimit || uint64_t(triangles.size()) + kept.size() > kLimit) {
    kept.clear();  // too big to index with uint32: drop the mesh rather than wrap indices
    unique = 0;
  }
  info.dropped_triangles = mesh_triangles.size() - kept.size();

  const bool first_geometry = triangles.empty();
  const uint32_t base = uint32_t(vertices.size());
  reserve_more(vertices, unique);
  for (size_t i = 0; i < weld.size() && unique > 0; ++i)
    if (weld[i] == vertices.size() - base) vertices.push_back(used_positions[i]);

  for (auto& t : kept)
    for (auto& index : t) index = weld[compact[index]];

  // 3. Classify (on mesh-local welded ids), then append with the scene offset.
  if (!heightfield && !kept.empty()) {
    const MeshClassification c = classify_welded_triangles(kept, unique);
    info.kind = c.kind;
    info.boundary_edges = c.boundary_edges;
    info.non_manifold_edges = c.non_manifold_edges;
    info.misoriented_edges = c.misoriented_edges;
    if (c.kind == MeshKind::closed)
      info.signed_volume = mesh_signed_volume(std::span<const Vec3>(vertices.data() + base, unique), kept);
  }

  const uint32_t mesh_index = uint32_t(meshes.size());
  reserve_more(triangles, kept.size());
  reserve_more(triangle_mesh, kept.size());
  for (auto& t : kept) {
    triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    triangle_mesh.push_back(mesh_index);
  }
  info.triangle_count = uint32_t(kept.size());

  // 4. Bounds over the stored (= used) vertices.
  for (size_t i = base; i < vertices.size(); ++i) {
    const Vec3& p = vertices[i];
    if (first_geometry && i == base) bounds.min = bounds.max = p;
    for (int k = 0; k < 3; ++k) {
      bounds.min[k] = std::min(bounds.min[k], p[k]);
      bounds.max[k] = std::max(bounds.max[k], p[k]);
    }
  }
  meshes.push_back(std::move(info));
  return meshes.back().dropped_triangles;
}

}  // namespace shadowtiles
