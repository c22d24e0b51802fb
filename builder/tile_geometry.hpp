// One tile's triangles as the dual-depth renderer and the entry rule see them: tile-local float
// footprints (what Embree intersects), per-triangle flags for the hit filter, each triangle's depth
// plane from the scene's double vertices, and, for the entry rule, which triangle lies across each
// edge. Built per tile by gather_tile_geometry, the edges' neighbours then by link_tile_neighbours.
// Thread safety: plain data; both functions only read the scene.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "builder/light_space_scene.hpp"

namespace shadowtiles {

// Per-geometry data the filter needs: which solid-bounding triangles face the light, and which
// belong to heightfields (solids closed by the far plane).
struct ClosedGeometryData {
  std::vector<uint8_t> front;
  std::vector<uint8_t> heightfield;
  std::vector<float> slack;
  std::vector<uint8_t> patch;  // patch triangles (builder/nearly_closed_meshes.hpp)
  bool open = false;  // the open meshes' geometry (its hits are collected under `surfaces`)
};

// A triangle's depth as a function of global texel coordinates, from the scene's double light-space
// vertices. Embree's hit distance is computed from the tile-local float BVH, so its rounding depends
// on where the tile starts; re-evaluating each hit here makes stored depths identical under any
// tiling (the ray and the triangle hit are the same, only the arithmetic is global).
struct DepthPlane {
  double u = 0, v = 0, depth = 0;  // anchor vertex
  double du = 0, dv = 0;           // depth change per texel along u and v
  double lowest = 0, highest = 0;  // the vertices' depth range: a hit is never outside it
  bool edge_on = true;             // parallel to the light: no plane to evaluate, keep Embree's depth

  static DepthPlane of(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
    DepthPlane plane;
    const double nx = (b.v - a.v) * (c.depth - a.depth) - (b.depth - a.depth) * (c.v - a.v);
    const double ny = (b.depth - a.depth) * (c.u - a.u) - (b.u - a.u) * (c.depth - a.depth);
    const double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
    plane.lowest = std::min({a.depth, b.depth, c.depth});
    plane.highest = std::max({a.depth, b.depth, c.depth});
    if (nz == 0) return plane;
    plane = {a.u, a.v, a.depth, -nx / nz, -ny / nz, plane.lowest, plane.highest, false};
    return plane;
  }
  // Depth at global texel coordinates (u, v); `embree_depth` where the triangle is edge-on.
  float at(double u, double v, float embree_depth) const {
    if (edge_on) return embree_depth;
    return float(std::clamp(depth + du * (u - this->u) + dv * (v - this->v), lowest, highest));
  }
};

// The triangle across one edge of another, in the same set: its primitive id and the index of the
// shared edge in it (edge k runs from vertex k to vertex k + 1); prim < 0 when there is none.
// `crossable`: the entry rule's cover may grow across the edge: there is a triangle, not edge-on, and
// it lies on the edge's other side (not folded under), by the scene's double vertices. Computed once
// per tile: the entry pass asks it for most texels near an edge.
struct EdgeNeighbour {
  int32_t prim = -1;
  int32_t edge = -1;
  bool crossable = false;
};
using EdgeNeighbours = std::array<EdgeNeighbour, 3>;

struct TileGeometry {
  std::vector<float> closed_vertices, open_vertices;    // xyz per vertex, 3 vertices per triangle
  ClosedGeometryData closed;                            // closed meshes and heightfields
  ClosedGeometryData open;                              // open meshes (filter data under `surfaces`)
  std::vector<DepthPlane> closed_planes, open_planes;   // by Embree primitive id
  // The entry rule's only: the triangle across each edge, and each triangle's three welded vertex ids.
  std::vector<EdgeNeighbours> closed_neighbours, open_neighbours;
  std::vector<uint32_t> closed_ids, open_ids;
  size_t open_count = 0;
};

// Every triangle of `tile` (and its patches, in the closed set) with its flags and plane; with
// `with_neighbours`, also the vertex ids link_tile_neighbours needs.
TileGeometry gather_tile_geometry(const LightSpaceScene& scene, TileCoord tile, bool with_neighbours);

// The entry rule's edge neighbours of a geometry gathered `with_neighbours`: the triangle across
// each edge, and whether it lies on the edge's other side. Apart from the gather, so a build times
// it as the entry rule's work rather than the ray casting's.
void link_tile_neighbours(const LightSpaceScene& scene, TileGeometry& geometry);

}  // namespace shadowtiles
