// Mesh classifier: is a triangle mesh closed (watertight and consistently oriented)? docs/architecture.md §4.
//
// Only closed meshes may contribute exit depths; everything else is one-sided. A mesh is closed when,
// after welding vertices with bit-identical positions, every undirected edge is used by exactly two
// triangles, once in each direction. Welding matters because importers (assimp) split a vertex per
// normal/uv, which would otherwise turn every hard edge or uv seam into two boundary edges.
//
// Cost: O(vertices + triangles) expected time (a hash map for welding, a radix sort for the edges),
// O(vertices + edges) memory.
// Errors: none; malformed triangles are skipped (see classify_mesh).
// Thread safety: pure functions, safe to call concurrently.
// Untrusted input: safe; indices are range-checked, non-finite positions are welded by bit pattern.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "builder/scene.hpp"

namespace shadowtiles {

struct MeshClassification {
  MeshKind kind = MeshKind::open;   // closed or open (never heightfield: that is the caller's choice)
  uint64_t edges = 0;               // distinct undirected edges after welding
  uint64_t boundary_edges = 0;      // used by one triangle (holes, borders)
  uint64_t non_manifold_edges = 0;  // used by three or more triangles
  uint64_t misoriented_edges = 0;   // used by two triangles in the same direction (a flipped face)
  uint64_t skipped_triangles = 0;   // out-of-range indices, or corners that weld to the same vertex
  // Signed volume (divergence theorem over the triangles). For a closed mesh it is negative when the
  // mesh is consistently oriented but inside out (normals pointing inward); it is meaningless for
  // open meshes.
  double signed_volume = 0;
};

// Maps each vertex to the first vertex with a bit-identical position (+0.0 and -0.0 are equal).
// Returns `weld[i]` = index of the representative, a dense id in [0, unique_count).
std::vector<uint32_t> weld_positions(std::span<const Vec3> vertices, uint32_t* unique_count = nullptr);

// Classifies triangles over `vertices` (welded internally). Triangles with an index out of range or
// with two corners welding to the same vertex are skipped and counted; they never make a mesh closed.
// An empty mesh (no usable triangle) is open.
MeshClassification classify_mesh(std::span<const Vec3> vertices,
                                 std::span<const std::array<uint32_t, 3>> triangles);

// Signed volume enclosed by the triangles (positive when a closed mesh's normals point outward).
// Out-of-range triangles are ignored.
double mesh_signed_volume(std::span<const Vec3> vertices, std::span<const std::array<uint32_t, 3>> triangles);

// The edge analysis alone, for triangles whose indices are already welded (each position appears once)
// and below `vertex_count`. Does not compute signed_volume. Used by Scene::add_mesh, which welds
// while it copies the vertices.
MeshClassification classify_welded_triangles(std::span<const std::array<uint32_t, 3>> triangles,
                                             uint32_t vertex_count);

}  // namespace shadowtiles
