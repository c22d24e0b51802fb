// Scene: the world as a triangle soup grouped into meshes, in world coordinates (double, so huge
// coordinates survive until the builder moves them into tile-local light space).
//
// Each mesh carries its classification (docs/architecture.md §4): closed meshes contribute exit depths, open
// ones are one-sided (exit = entry), heightfield meshes are solid below (exit = far plane).
// Built by the scene loader (builder/scene_loader.hpp) or by hand in tests via add_mesh().
// Thread safety: immutable once built; concurrent reads are safe.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "codec/light_frame.hpp"

namespace shadowtiles {

enum class MeshKind : uint8_t { open, closed, heightfield };
const char* mesh_kind_name(MeshKind kind);

struct MeshInfo {
  std::string name;
  uint32_t first_triangle = 0;  // into Scene::triangles
  uint32_t triangle_count = 0;
  MeshKind kind = MeshKind::open;
  // Why a mesh is open, for the log: edges used by one triangle, by more than two, or twice in the
  // same direction (inconsistent orientation).
  uint64_t boundary_edges = 0;
  uint64_t non_manifold_edges = 0;
  uint64_t misoriented_edges = 0;
  uint64_t dropped_triangles = 0;  // degenerate or malformed input triangles add_mesh left out
  // Closed meshes only: enclosed volume, negative when the mesh is inside out (normals inward; the
  // renderer then sees a back face first and falls back to entry = exit, conservatively).
  double signed_volume = 0;
  // Accepted as a solid by the winding-number test (builder/nearly_closed_meshes.hpp): kind is closed and
  // its holes are closed by patch triangles (Scene::patch_triangles) that only the exit counter and caps see.
  bool nearly_closed = false;
};

struct Scene {
  std::vector<Vec3> vertices;                     // world space
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise = front face
  std::vector<uint32_t> triangle_mesh;            // mesh index per triangle
  std::vector<MeshInfo> meshes;
  // Patches over the holes of nearly closed meshes (builder/nearly_closed_meshes.hpp), over `vertices`
  // (their loops' centroids are appended there, inside the bounds). Not geometry: they take part only in
  // the dual-depth exit counter and the exit caps, never as a first hit, an occluder or a receiver.
  std::vector<std::array<uint32_t, 3>> patch_triangles;
  std::vector<uint32_t> patch_mesh;               // mesh index per patch triangle
  bool nearly_closed_tested = false;              // close_nearly_closed_meshes ran on this scene
  WorldBounds bounds;                             // of the vertices used by triangles

  size_t triangle_count() const { return triangles.size(); }

  // Appends a mesh (vertices are world space; indices into `mesh_vertices`), drops degenerate and
  // non-finite triangles (returns how many), classifies it (closed/open) unless `kind` is
  // heightfield, and grows the bounds.
  // Dropped: an index out of range, a repeated index, a non-finite corner, or zero area, meaning
  // |cross(b-a, c-a)| <= 1e-10 * (longest edge)^2 (the triangle's height is under 1e-10 of its longest
  // edge). Relative, so the test is scale invariant; far below float precision, so no triangle of
  // float input that has any extent is dropped.
  // Only vertices used by kept triangles are stored, and those with bit-identical positions are
  // merged (the scene keeps positions only, so nothing is lost; importers split them per normal/uv).
  // A mesh is always appended to `meshes`, even when every triangle was dropped. If the scene would
  // exceed 2^32 - 1 vertices or triangles, the whole mesh is dropped (and counted).
  // Untrusted input: safe (every index is checked).
  uint64_t add_mesh(const std::string& name, const std::vector<Vec3>& mesh_vertices,
                    const std::vector<std::array<uint32_t, 3>>& mesh_triangles, bool heightfield = false);
};

}  // namespace shadowtiles
