#include "builder/tile_geometry.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "builder/stable_key_sort.hpp"

namespace shadowtiles {
namespace {

// Receivers on an exit surface lie anywhere in the texel, not only at its centre: on a surface
// steep to the light their depth is up to half a texel's slope shallower than the centre's. The
// exit is pulled back by that much (plus the margin), so they stay shadowed; a surface parallel to
// the light gives infinite slack and the interval collapses to the entry (conservative).
float exit_slack(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  double nx = (b.v - a.v) * (c.depth - a.depth) - (b.depth - a.depth) * (c.v - a.v);
  double ny = (b.depth - a.depth) * (c.u - a.u) - (b.u - a.u) * (c.depth - a.depth);
  double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  if (nz == 0) return std::numeric_limits<float>::infinity();
  return float(0.5 * (std::fabs(nx) + std::fabs(ny)) / std::fabs(nz));
}

// Links triangles that share an edge (the same two welded vertex ids, so the same float endpoints
// in the tile's footprint). `ids` holds three vertex ids per triangle; `skip` marks triangles that
// are no surface (patches). An edge shared by more than two triangles links none of them.
std::vector<EdgeNeighbours> link_edge_neighbours(const std::vector<uint32_t>& ids, const std::vector<uint8_t>& skip) {
  const size_t count = ids.size() / 3;
  std::vector<EdgeNeighbours> neighbours(count);
  std::vector<std::pair<uint64_t, uint32_t>> edges;  // (edge key, triangle * 3 + edge)
  edges.reserve(ids.size());
  for (size_t t = 0; t < count; ++t) {
    if (skip[t]) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint64_t a = ids[t * 3 + k], b = ids[t * 3 + (k + 1) % 3];
      edges.push_back({std::min(a, b) << 32 | std::max(a, b), uint32_t(t * 3 + k)});
    }
  }
  stable_sort_by_key(edges);  // edges were pushed in increasing value order: std::sort's order
  for (size_t i = 0; i < edges.size();) {
    size_t end = i + 1;
    while (end < edges.size() && edges[end].first == edges[i].first) ++end;
    if (end - i == 2) {
      const uint32_t p = edges[i].second, q = edges[i + 1].second;
      neighbours[p / 3][p % 3] = {int32_t(q / 3), int32_t(q % 3)};
      neighbours[q / 3][q % 3] = {int32_t(p / 3), int32_t(p % 3)};
    }
    i = end;
  }
  return neighbours;
}

// Whether the triangle across edge k of `prim` lies on that edge's other side (not folded under it):
// the two opposite vertices on the shared edge's two sides, from the scene's double vertices.
bool lies_across(const LightSpaceScene& scene, const std::vector<uint32_t>& ids, uint32_t prim, int k,
                 EdgeNeighbour across) {
  auto side = [&](uint32_t p, uint32_t q, uint32_t r) {
    const LightSpacePoint &a = scene.vertex(p), &b = scene.vertex(q), &c = scene.vertex(r);
    return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  };
  const uint32_t a = ids[size_t(prim) * 3 + size_t(k)], b = ids[size_t(prim) * 3 + size_t(k + 1) % 3];
  const double mine = side(a, b, ids[size_t(prim) * 3 + size_t(k + 2) % 3]);
  const double theirs = side(a, b, ids[size_t(across.prim) * 3 + size_t(across.edge + 2) % 3]);
  return (mine > 0 && theirs < 0) || (mine < 0 && theirs > 0);
}

void mark_crossable(const LightSpaceScene& scene, const std::vector<uint32_t>& ids,
                    const std::vector<DepthPlane>& planes, std::vector<EdgeNeighbours>& neighbours) {
  for (size_t t = 0; t < neighbours.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      EdgeNeighbour& n = neighbours[t][size_t(k)];
      n.crossable = n.prim >= 0 && !planes[size_t(n.prim)].edge_on && lies_across(scene, ids, uint32_t(t), k, n);
    }
}

// Front-facing toward the light: counter-clockwise seen from the light, i.e. the normal's depth
// component is negative (the light travels +depth in a right-handed frame).
bool faces_light(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  return nz <= 0.0;  // edge-on counts as front: the counter then never closes early (conservative)
}

}  // namespace

TileGeometry gather_tile_geometry(const LightSpaceScene& scene, TileCoord tile, bool with_neighbours) {
  TileGeometry geometry;
  std::vector<uint32_t>& closed_ids = geometry.closed_ids;
  std::vector<uint32_t>& open_ids = geometry.open_ids;
  geometry.open.open = true;
  const double u0 = double(tile.x) * scene.layout().tile_size();
  const double v0 = double(tile.y) * scene.layout().tile_size();
  const Scene& world = scene.scene();
  auto emit = [&](std::vector<float>& out, const LightSpacePoint& p) {
    out.push_back(float(p.u - u0));
    out.push_back(float(p.v - v0));
    out.push_back(float(p.depth));
  };
  // One triangle into the closed or the open set: its vertices, per-triangle flags and depth plane.
  auto add = [&](bool closed, uint32_t a_id, uint32_t b_id, uint32_t c_id, bool heightfield, bool patch) {
    const LightSpacePoint& a = scene.vertex(a_id);
    const LightSpacePoint& b = scene.vertex(b_id);
    const LightSpacePoint& c = scene.vertex(c_id);
    auto& set = closed ? geometry.closed : geometry.open;
    auto& vertices = closed ? geometry.closed_vertices : geometry.open_vertices;
    emit(vertices, a);
    emit(vertices, b);
    emit(vertices, c);
    if (with_neighbours) (closed ? closed_ids : open_ids).insert((closed ? closed_ids : open_ids).end(), {a_id, b_id, c_id});
    set.front.push_back(faces_light(a, b, c) ? 1 : 0);
    set.heightfield.push_back(heightfield ? 1 : 0);
    set.slack.push_back(exit_slack(a, b, c));
    set.patch.push_back(patch ? 1 : 0);
    (closed ? geometry.closed_planes : geometry.open_planes).push_back(DepthPlane::of(a, b, c));
  };
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    const MeshKind kind = world.meshes[world.triangle_mesh[t]].kind;
    const bool closed = kind != MeshKind::open;
    add(closed, tri[0], tri[1], tri[2], kind == MeshKind::heightfield, false);
    if (!closed) ++geometry.open_count;
  }
  // Patches close nearly closed meshes for the exit counter only (resolve_interval never takes one for
  // the first hit); they join the closed geometry, whose hits are all collected.
  for (uint32_t t : scene.patches_of(tile)) {
    const auto& tri = world.patch_triangles[t];
    add(true, tri[0], tri[1], tri[2], false, true);
  }
  return geometry;
}

void link_tile_neighbours(const LightSpaceScene& scene, TileGeometry& geometry) {
  // Gathered with `with_neighbours`: three vertex ids per triangle of each set.
  assert(geometry.closed_ids.size() == 3 * geometry.closed_planes.size() &&
         geometry.open_ids.size() == 3 * geometry.open_planes.size());
  geometry.closed_neighbours = link_edge_neighbours(geometry.closed_ids, geometry.closed.patch);
  geometry.open_neighbours = link_edge_neighbours(geometry.open_ids, geometry.open.patch);
  mark_crossable(scene, geometry.closed_ids, geometry.closed_planes, geometry.closed_neighbours);
  mark_crossable(scene, geometry.open_ids, geometry.open_planes, geometry.open_neighbours);
}

}  // namespace shadowtiles
