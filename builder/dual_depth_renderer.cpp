#include "builder/dual_depth_renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <limits>
#include <vector>

#include "builder/receiver_surface_caps.hpp"
#include "common/float_rounding.hpp"
#include "builder/ground_truth.hpp"
#include "builder/second_layer_caps.hpp"
#include "builder/second_layer_rule.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

constexpr unsigned kPacket = 16;

struct ClosedHit {
  float t;
  uint32_t prim;
  bool front;
  bool heightfield;
  float slack;  // how much shallower the triangle gets within half a texel (normalised depth)
  bool open = false;  // an open-mesh hit (collected only under the `surfaces` contract)
  bool patch = false;  // a patch over a nearly closed mesh's hole: counts, but is never a surface
};

// Per-geometry data the filter needs: which solid-bounding triangles face the light, and which
// belong to heightfields (solids closed by the far plane).
struct ClosedGeometryData {
  std::vector<uint8_t> front;
  std::vector<uint8_t> heightfield;
  std::vector<float> slack;
  std::vector<uint8_t> patch;  // patch triangles (builder/nearly_closed_meshes.hpp)
  bool open = false;  // the open meshes' geometry (its hits are collected under `surfaces`)
};

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

// Intersect context extended with per-lane hit lists: the filter sees ray ids, not lanes.
struct CollectContext {
  RTCIntersectContext base;
  std::array<std::vector<ClosedHit>, kPacket>* lanes;
};

// Records every closed-mesh hit and rejects it so traversal continues: afterwards each lane holds
// all closed hits up to the nearest accepted (open-mesh) hit.
void collect_closed_hits(const RTCFilterFunctionNArguments* args) {
  auto* context = reinterpret_cast<CollectContext*>(args->context);
  auto* data = static_cast<const ClosedGeometryData*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    unsigned lane = RTCRayN_id(args->ray, args->N, i);
    float t = RTCRayN_tfar(args->ray, args->N, i);
    uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
    (*context->lanes)[lane % kPacket].push_back(
        {t, prim, data->front[prim] != 0, data->heightfield[prim] != 0, data->slack[prim], data->open,
         data->patch[prim] != 0});
    args->valid[i] = 0;
  }
}

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
struct EdgeNeighbour {
  int32_t prim = -1;
  int32_t edge = -1;
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
  std::sort(edges.begin(), edges.end());
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

// Front-facing toward the light: counter-clockwise seen from the light, i.e. the normal's depth
// component is negative (the light travels +depth in a right-handed frame).
bool faces_light(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  return nz <= 0.0;  // edge-on counts as front: the counter then never closes early (conservative)
}

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
  if (with_neighbours) {
    geometry.closed_neighbours = link_edge_neighbours(closed_ids, geometry.closed.patch);
    geometry.open_neighbours = link_edge_neighbours(open_ids, geometry.open.patch);
  }
  return geometry;
}

// Attaches a triangle soup as one geometry; returns its id.
unsigned attach_triangles(RTCDevice device, RTCScene scene, const std::vector<float>& vertices,
                          ClosedGeometryData* filter_data) {
  size_t triangle_count = vertices.size() / 9;
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Embree reads vertex buffers with 16-byte loads: one float of padding past the end.
  auto* vertex_buffer = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), triangle_count * 3));
  std::copy(vertices.begin(), vertices.end(), vertex_buffer);
  auto* index_buffer = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), triangle_count));
  for (uint32_t i = 0; i < triangle_count * 3; ++i) index_buffer[i] = i;
  if (filter_data) {
    rtcSetGeometryUserData(geometry, filter_data);
    rtcSetGeometryIntersectFilterFunction(geometry, collect_closed_hits);
  }
  rtcCommitGeometry(geometry);
  unsigned id = rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  return id;
}

// Combines one ray's hits into its interval (rules in the header).
DepthInterval resolve_interval(std::vector<ClosedHit>& closed_hits, float open_t, const DualDepthOptions& options) {
  const float exit_margin = options.exit_margin;
  // With exit caps, the cap (the shallowest receiver surface inside the texel's square, the exit
  // triangle included) already bounds what the slack stands for, exactly; the slack is dropped then,
  // because it belongs to whichever triangle the centre ray hit, and on an edge shared by two
  // triangles that choice can differ between tilings.
  const bool use_slack = !options.cap_exits_at_receiver_surfaces || options.open_exit_at_far_plane;
  // Closed hits beyond the nearest open hit were recorded before that hit shortened the ray.
  std::erase_if(closed_hits, [&](const ClosedHit& h) { return h.t > open_t; });
  // Spatial splits may report one triangle twice.
  std::sort(closed_hits.begin(), closed_hits.end(), [](const ClosedHit& a, const ClosedHit& b) {
    return a.prim < b.prim;
  });
  closed_hits.erase(std::unique(closed_hits.begin(), closed_hits.end(),
                                [](const ClosedHit& a, const ClosedHit& b) { return a.prim == b.prim; }),
                    closed_hits.end());
  std::sort(closed_hits.begin(), closed_hits.end(), [](const ClosedHit& a, const ClosedHit& b) {
    return a.t != b.t ? a.t < b.t : a.front > b.front;
  });

  // The first hit is the first real surface: a patch is no surface (a ray entering through a hole
  // facing the light first hits the mesh's inside).
  size_t first_real = 0;
  while (first_real < closed_hits.size() && closed_hits[first_real].patch) ++first_real;
  DepthInterval interval;  // miss: [1, +inf)
  if (first_real == closed_hits.size() && open_t == std::numeric_limits<float>::infinity()) return interval;
  if (first_real == closed_hits.size() || open_t <= closed_hits[first_real].t) {
    interval.lower = open_t;
    interval.upper = options.open_exit_at_far_plane ? std::max(open_t, 1.0f) : open_t;
    return interval;
  }
  interval.lower = closed_hits[first_real].t;
  interval.upper = interval.lower;
  // The solid is the union of closed meshes (nearly closed ones with their patches) and heightfields; a
  // heightfield's solid is closed by the far plane. The ray is inside while the counter is positive,
  // counted from the light, patches before the first hit included; the exit is where it returns to 0
  // at or after the first hit (at the first hit itself when that is a back face: upper = lower).
  int depth = 0, heightfield_depth = 0;
  for (size_t i = 0; i < closed_hits.size(); ++i) {
    const ClosedHit& hit = closed_hits[i];
    depth += hit.front ? 1 : -1;
    if (hit.heightfield) heightfield_depth += hit.front ? 1 : -1;
    if (depth < 0) return interval;  // inconsistent: stay conservative
    if (depth == 0 && i >= first_real) {
      interval.upper = std::max(interval.lower, hit.t - exit_margin - (use_slack ? hit.slack : 0.0f));
      return interval;
    }
  }
  // Still inside: only a heightfield (solid down to the far plane) with no open surface below
  // gives an exit, the far plane, pulled back by the margin like any exit: receivers beyond the far
  // plane are answered as on it, and must stay shadowed under terrain.
  if (heightfield_depth > 0 && open_t == std::numeric_limits<float>::infinity())
    interval.upper = std::max(interval.lower, 1.0f - exit_margin);
  return interval;
}

// The `surfaces` contract (docs/receiver-contracts.md): `hits` holds every hit on the ray, closed
// and open. Upper = the second receiver surface less the margin: the first hit deeper than the first
// surface by more than the coplanar epsilon that is not inside a closed solid (an exit face is a
// surface; faces strictly inside a solid, heightfields included, are not receivers). No second
// surface: upper = 1 (nothing lies beyond the last surface; a query there is off every surface).
DepthInterval resolve_surfaces_interval(std::vector<ClosedHit>& hits, const DualDepthOptions& options) {
  const bool use_slack = !options.cap_exits_at_receiver_surfaces;
  std::erase_if(hits, [](const ClosedHit& h) { return h.patch; });  // patches belong to `anywhere` only
  std::sort(hits.begin(), hits.end(), [](const ClosedHit& a, const ClosedHit& b) {
    return a.open != b.open ? a.open < b.open : a.prim < b.prim;
  });
  hits.erase(std::unique(hits.begin(), hits.end(),
                         [](const ClosedHit& a, const ClosedHit& b) { return a.open == b.open && a.prim == b.prim; }),
             hits.end());
  std::sort(hits.begin(), hits.end(), [](const ClosedHit& a, const ClosedHit& b) {
    return a.t != b.t ? a.t < b.t : a.front > b.front;
  });
  DepthInterval interval;  // miss: [1, +inf)
  if (hits.empty()) return interval;
  interval.lower = hits.front().t;
  const float same_surface = float(interval.lower + options.coplanar_epsilon);
  int solid = 0, closed_solid = 0;  // counters: all solids, closed meshes alone (no heightfields)
  for (size_t i = 0; i < hits.size(); ++i) {
    const ClosedHit& hit = hits[i];
    const int before = solid;
    if (!hit.open) {
      solid += hit.front ? 1 : -1;
      if (!hit.heightfield) closed_solid += hit.front ? 1 : -1;
    }
    if (i == 0 || hit.t <= same_surface) continue;  // the first surface, or a coplanar duplicate of it
    const bool receiver = hit.open ? before <= 0 : (before <= 0 || solid <= 0);
    if (!receiver) continue;
    interval.upper = std::max(interval.lower, hit.t - options.exit_margin - (use_slack ? hit.slack : 0.0f));
    return interval;
  }
  // Inside a closed mesh that never exits (inconsistent): stay conservative.
  interval.upper = closed_solid > 0 ? interval.lower : 1.0f;
  return interval;
}

constexpr double kEntrySquareHalf = 0.51;

// min(lower, deepest + tolerance - slack), rounded up to a float and one float step more: never
// below the exact bound, nor below verify's reference (builder/reference_entry_bounds.hpp), which
// evaluates the same planes another way.
float entry_bound(double deepest, float lower, float slack, float tolerance) {
  const double entry = deepest + double(tolerance) - double(slack);
  if (entry >= double(lower)) return lower;
  return std::clamp(next_float_up(float_at_least(entry)), 0.0f, lower);
}

// The entry rule (DualDepthOptions::entry_slack). `first_prim` is the centre ray's first-hit triangle
// (in the open set when `open`), (cu, cv) the texel centre in tile-local texels, (global_u, global_v)
// in the map's. The rule needs triangles whose footprints cover the texel's whole square S: then the
// visible depth at every point of S is at most the depth of a triangle there, so a lit receiver is no
// deeper than the largest of their depths over S plus `tolerance` (the ground truth's ray offset),
// and with a query bias of at least `slack` any value from that depth less `slack` lights it. Else (S reaches a hole, a mesh's border, a
// silhouette fold or an edge-on triangle) lower stays the first hit.
//
// The cover is grown from the first-hit triangle across every edge that meets S (the square grown by
// a hundredth of a texel, for the footprints' float rounding) to the triangle on that edge's other
// side. It holds S when every such edge has exactly one such triangle, lying on the other side (not
// folded under), and the set stays small: the union's boundary then lies on edges that miss S (around
// a vertex in S the triangles form a closed, unfolded fan), and S, connected and holding the centre,
// lies inside it. docs/receiver-contracts.md, "The entry rule", has the argument.
constexpr int kMaxCoverTriangles = 24;  // more: lower stays the first hit (a bounded cost per texel)
float entry_lower(const TileGeometry& geometry, const LightSpaceScene& scene, bool open, uint32_t first_prim,
                  double cu, double cv, double global_u, double global_v, float lower, float slack, float tolerance) {
  const auto& planes = open ? geometry.open_planes : geometry.closed_planes;
  const auto& vertices = open ? geometry.open_vertices : geometry.closed_vertices;
  const auto& neighbours = open ? geometry.open_neighbours : geometry.closed_neighbours;
  const auto& ids = open ? geometry.open_ids : geometry.closed_ids;
  const double corner_u[4] = {cu - kEntrySquareHalf, cu + kEntrySquareHalf, cu - kEntrySquareHalf, cu + kEntrySquareHalf};
  const double corner_v[4] = {cv - kEntrySquareHalf, cv - kEntrySquareHalf, cv + kEntrySquareHalf, cv + kEntrySquareHalf};
  // Whether a footprint edge may meet the grown square: false only when its bounding box misses the
  // square or the square lies strictly on one side of its line.
  auto edge_meets_square = [&](const float* p, const float* q) {
    if (std::max(p[0], q[0]) < corner_u[0] || std::min(p[0], q[0]) > corner_u[1] ||
        std::max(p[1], q[1]) < corner_v[0] || std::min(p[1], q[1]) > corner_v[2])
      return false;
    int positive = 0, negative = 0;
    for (int c = 0; c < 4; ++c) {
      const double side = (double(q[0]) - p[0]) * (corner_v[c] - p[1]) - (double(q[1]) - p[1]) * (corner_u[c] - p[0]);
      positive += side > 0;
      negative += side < 0;
    }
    return positive != 4 && negative != 4;
  };
  // Side of point r of the line p -> q, from the scene's double light-space vertices.
  auto side = [&](uint32_t p, uint32_t q, uint32_t r) {
    const LightSpacePoint &a = scene.vertex(p), &b = scene.vertex(q), &c = scene.vertex(r);
    return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  };
  std::array<int32_t, kMaxCoverTriangles> cover;
  int count = 0;
  cover[count++] = int32_t(first_prim);
  for (int i = 0; i < count; ++i) {
    const int32_t prim = cover[size_t(i)];
    if (planes[size_t(prim)].edge_on) return lower;
    const float* x = &vertices[size_t(prim) * 9];
    for (int k = 0; k < 3; ++k) {
      const int j = (k + 1) % 3;
      if (!edge_meets_square(x + 3 * k, x + 3 * j)) continue;
      const EdgeNeighbour across = neighbours[size_t(prim)][size_t(k)];
      if (across.prim < 0 || planes[size_t(across.prim)].edge_on) return lower;
      const uint32_t a = ids[size_t(prim) * 3 + k], b = ids[size_t(prim) * 3 + j];
      const uint32_t mine = ids[size_t(prim) * 3 + (k + 2) % 3];
      const uint32_t theirs = ids[size_t(across.prim) * 3 + (across.edge + 2) % 3];
      const double my_side = side(a, b, mine), their_side = side(a, b, theirs);
      if (!((my_side > 0 && their_side < 0) || (my_side < 0 && their_side > 0))) return lower;  // folded
      if (std::find(cover.begin(), cover.begin() + count, across.prim) != cover.begin() + count) continue;
      if (count == kMaxCoverTriangles) return lower;
      cover[size_t(count++)] = across.prim;
    }
  }
  // A triangle's largest depth over its part of the square is at most its plane's over the whole
  // square (at the centre, in double, plus half a texel of slope along each axis) and at most its
  // deepest vertex.
  double deepest = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < count; ++i) {
    const DepthPlane& p = planes[size_t(cover[size_t(i)])];
    const double over_square =
        p.depth + p.du * (global_u - p.u) + p.dv * (global_v - p.v) + 0.5 * (std::fabs(p.du) + std::fabs(p.dv));
    deepest = std::max(deepest, std::min(over_square, p.highest));
  }
  return entry_bound(deepest, lower, slack, tolerance);
}

// The entry pass over a tile, in the common cases first: a square inside its first-hit triangle, or
// inside it and the triangle across the one edge that crosses it (the cover entry_lower would grow).
// Per triangle, once for a run of texels that hit it: its edge lines and plane in global texel
// coordinates, and for each edge the triangle across it (when it lies on the other side, not folded)
// with that triangle's two other edge lines and plane. A square lies inside an edge's half-plane when
// the line's value at its centre exceeds the grown square's half-extent along the line's normal.
// Anything else goes to entry_lower's search.
class EntryFastPath {
 public:
  EntryFastPath(const TileGeometry& geometry, const LightSpaceScene& scene, double tile_u0, double tile_v0)
      : geometry_(geometry), scene_(scene), tile_u0_(tile_u0), tile_v0_(tile_v0) {}

  // The largest depth over the square centred at global (gu, gv) of the cover found, for a first hit
  // `key` (prim | open flag); NaN when neither common case applies.
  double deepest(uint32_t key, bool open, uint32_t prim, double gu, double gv) {
    const double none = std::numeric_limits<double>::quiet_NaN();
    if (key != key_) prepare(open, prim, key);
    if (!triangle_.usable) return none;
    int crossed = -1;
    for (int k = 0; k < 3; ++k) {
      if (triangle_.edge[k].holds(gu, gv)) continue;
      if (crossed >= 0) return none;
      crossed = k;
    }
    const double own = triangle_.plane.deepest(gu, gv);
    if (crossed < 0) return own;
    const Across& across = across_[crossed];
    if (!across.usable || !across.edge[0].holds(gu, gv) || !across.edge[1].holds(gu, gv)) return none;
    return std::max(own, across.plane.deepest(gu, gv));
  }

 private:
  struct Line {  // a (gu) + b (gv) + c, positive inside
    double a = 0, b = 0, c = 0, margin = 0;
    bool holds(double gu, double gv) const { return a * gu + b * gv + c > margin; }
  };
  struct Plane {  // the plane's largest depth over the square centred at (gu, gv), at most its deepest vertex
    double du = 0, dv = 0, c = 0, highest = 0;
    double deepest(double gu, double gv) const { return std::min(du * gu + dv * gv + c, highest); }
  };
  struct Triangle {
    bool usable = false;
    Line edge[3];
    Plane plane;
  };
  struct Across {
    bool usable = false;
    Line edge[2];  // the triangle across's edges other than the shared one
    Plane plane;
  };

  // Edge k of a footprint (tile-local floats) as a global line, inner side positive.
  Line line(const float* t, int k, double orientation) const {
    const float* p = t + 3 * k;
    const float* q = t + 3 * ((k + 1) % 3);
    const double a = -(double(q[1]) - p[1]), b = double(q[0]) - p[0];
    return {orientation * a, orientation * b, -orientation * (a * (tile_u0_ + p[0]) + b * (tile_v0_ + p[1])),
            kEntrySquareHalf * (std::fabs(a) + std::fabs(b))};
  }
  static Plane plane_of(const DepthPlane& p) {
    return {p.du, p.dv, p.depth - p.du * p.u - p.dv * p.v + 0.5 * (std::fabs(p.du) + std::fabs(p.dv)), p.highest};
  }
  // The footprint of `prim` and its orientation (+1 counter-clockwise, -1 clockwise, 0 none or edge-on).
  double orientation(bool open, uint32_t prim, const float** t) const {
    *t = &(open ? geometry_.open_vertices : geometry_.closed_vertices)[size_t(prim) * 9];
    const float* x = *t;
    const double area = (double(x[3]) - x[0]) * (double(x[7]) - x[1]) - (double(x[4]) - x[1]) * (double(x[6]) - x[0]);
    if ((open ? geometry_.open_planes : geometry_.closed_planes)[prim].edge_on || area == 0) return 0;
    return area > 0 ? 1.0 : -1.0;
  }
  double side(uint32_t p, uint32_t q, uint32_t r) const {
    const LightSpacePoint &a = scene_.vertex(p), &b = scene_.vertex(q), &c = scene_.vertex(r);
    return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  }

  void prepare(bool open, uint32_t prim, uint32_t key) {
    key_ = key;
    const float* t;
    const double own = orientation(open, prim, &t);
    triangle_.usable = own != 0;
    if (!triangle_.usable) return;
    const auto& planes = open ? geometry_.open_planes : geometry_.closed_planes;
    const auto& neighbours = open ? geometry_.open_neighbours : geometry_.closed_neighbours;
    const auto& ids = open ? geometry_.open_ids : geometry_.closed_ids;
    for (int k = 0; k < 3; ++k) triangle_.edge[k] = line(t, k, own);
    triangle_.plane = plane_of(planes[prim]);
    for (int k = 0; k < 3; ++k) {
      Across& across = across_[k];
      const EdgeNeighbour n = neighbours[prim][size_t(k)];
      const float* o;
      const double theirs = n.prim < 0 ? 0 : orientation(open, uint32_t(n.prim), &o);
      across.usable = theirs != 0;
      if (!across.usable) continue;
      // Not folded: the two opposite vertices on the shared edge's two sides (double vertices).
      const uint32_t a = ids[size_t(prim) * 3 + k], b = ids[size_t(prim) * 3 + (k + 1) % 3];
      const double mine_side = side(a, b, ids[size_t(prim) * 3 + (k + 2) % 3]);
      const double their_side = side(a, b, ids[size_t(n.prim) * 3 + (n.edge + 2) % 3]);
      across.usable = (mine_side > 0 && their_side < 0) || (mine_side < 0 && their_side > 0);
      if (!across.usable) continue;
      across.edge[0] = line(o, (n.edge + 1) % 3, theirs);
      across.edge[1] = line(o, (n.edge + 2) % 3, theirs);
      across.plane = plane_of(planes[size_t(n.prim)]);
    }
  }

  const TileGeometry& geometry_;
  const LightSpaceScene& scene_;
  double tile_u0_, tile_v0_;
  uint32_t key_ = std::numeric_limits<uint32_t>::max();
  Triangle triangle_;
  Across across_[3];
};

}  // namespace

void DualDepthStats::add(const DualDepthStats& other) {
  rays += other.rays;
  hits += other.hits;
  exits += other.exits;
  triangles += other.triangles;
  bvh_seconds += other.bvh_seconds;
  ray_seconds += other.ray_seconds;
  cap_seconds += other.cap_seconds;
  entry_seconds += other.entry_seconds;
}

DualDepthRenderer::DualDepthRenderer(const EmbreeDevice& device, const LightSpaceScene& scene,
                                     DualDepthOptions options)
    : device_(device), scene_(scene), options_(options) {}

Result<TileIntervals> DualDepthRenderer::render_centre(TileCoord tile, DualDepthStats* stats,
                                                      RenderBuffers* buffers) const {
  const uint32_t size = scene_.layout().tile_size();
  TileIntervals intervals;
  if (buffers) intervals = std::move(buffers->intervals);
  intervals.size = size;
  intervals.texels.assign(size_t(size) * size, DepthInterval{});
  const bool entry_rule = options_.receivers == ReceiverContract::surfaces && options_.entry_slack > 0;
  intervals.entry_lower.clear();
  if (entry_rule) intervals.entry_lower.assign(size_t(size) * size, 1.0f);
  DualDepthStats local;
  if (!scene_.layout().contains(tile))
    return make_error(ErrorCode::invalid_input, "tile outside the map");
  if (scene_.triangles_of(tile).empty()) {
    if (stats) stats->add(local);
    return intervals;
  }

  auto bvh_start = Clock::now();
  TileGeometry geometry = gather_tile_geometry(scene_, tile, entry_rule);
  EmbreeScene rtc_scene(rtcNewScene(device_.get()));
  rtcSetSceneFlags(rtc_scene.get(), RTC_SCENE_FLAG_ROBUST);
  unsigned closed_id = RTC_INVALID_GEOMETRY_ID;
  if (!geometry.closed.front.empty())
    closed_id = attach_triangles(device_.get(), rtc_scene.get(), geometry.closed_vertices, &geometry.closed);
  unsigned open_id = RTC_INVALID_GEOMETRY_ID;
  const bool surfaces = options_.receivers == ReceiverContract::surfaces;
  if (geometry.open_count)
    open_id = attach_triangles(device_.get(), rtc_scene.get(), geometry.open_vertices,
                               surfaces ? &geometry.open : nullptr);
  rtcCommitScene(rtc_scene.get());
  if (RTCError error = rtcGetDeviceError(device_.get()); error != RTC_ERROR_NONE)
    return make_error(ErrorCode::io_error, "embree failed to build the tile BVH (error " +
                                               std::to_string(int(error)) + ")");
  local.triangles = geometry.closed.front.size() + geometry.open_count;
  local.bvh_seconds = seconds_since(bvh_start);

  auto ray_start = Clock::now();
  // The entry rule's: the row's first-hit triangles, primitive id with the open set's flag.
  constexpr uint32_t kOpenFlag = 1u << 31;
  std::vector<uint32_t> first_hits(entry_rule ? size : 0);
  std::array<std::vector<ClosedHit>, kPacket> lanes;
  CollectContext context;
  rtcInitIntersectContext(&context.base);
  context.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  context.lanes = &lanes;
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[kPacket];
  const float inf = std::numeric_limits<float>::infinity();
  const uint64_t tile_u0 = uint64_t(tile.x) * size, tile_v0 = uint64_t(tile.y) * size;
  // The entry rule's pass runs row by row while the row is in cache, timed apart from the rays.
  EntryFastPath fast(geometry, scene_, double(tile_u0), double(tile_v0));
  auto entry_row = [&](uint32_t v) {
    for (uint32_t u = 0; u < size; ++u) {
      const size_t i = size_t(v) * size + u;
      const float lower = intervals.texels[i].lower;
      if (!(lower < 1.0f)) continue;
      const bool open = (first_hits[u] & kOpenFlag) != 0;
      const uint32_t prim = first_hits[u] & ~kOpenFlag;
      const double gu = double(tile_u0) + u + 0.5, gv = double(tile_v0) + v + 0.5;
      const double deepest = fast.deepest(first_hits[u], open, prim, gu, gv);
      intervals.entry_lower[i] =
          deepest == deepest ? entry_bound(deepest, lower, options_.entry_slack, options_.entry_tolerance)
                             : entry_lower(geometry, scene_, open, prim, u + 0.5, v + 0.5, gu, gv, lower,
                                           options_.entry_slack, options_.entry_tolerance);
    }
  };
  for (uint32_t v = 0; v < size; ++v) {
    for (uint32_t u_start = 0; u_start < size; u_start += kPacket) {
      for (unsigned lane = 0; lane < kPacket; ++lane) {
        uint32_t u = u_start + lane;
        valid[lane] = u < size ? -1 : 0;
        packet.ray.org_x[lane] = float(u) + 0.5f;
        packet.ray.org_y[lane] = float(v) + 0.5f;
        packet.ray.org_z[lane] = 0.0f;
        packet.ray.dir_x[lane] = 0.0f;
        packet.ray.dir_y[lane] = 0.0f;
        packet.ray.dir_z[lane] = 1.0f;
        packet.ray.tnear[lane] = 0.0f;
        packet.ray.tfar[lane] = inf;
        packet.ray.time[lane] = 0.0f;
        packet.ray.mask[lane] = 0xFFFFFFFFu;
        packet.ray.id[lane] = lane;
        packet.ray.flags[lane] = 0;
        packet.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
        lanes[lane].clear();
      }
      rtcIntersect16(valid, rtc_scene.get(), &context.base, &packet);
      for (unsigned lane = 0; lane < kPacket && u_start + lane < size; ++lane) {
        // Every hit's depth re-evaluated at the global texel centre (see DepthPlane).
        const double centre_u = double(tile_u0) + (u_start + lane) + 0.5, centre_v = double(tile_v0) + v + 0.5;
        bool open_hit = packet.hit.geomID[lane] == open_id && open_id != RTC_INVALID_GEOMETRY_ID;
        float open_t = open_hit ? geometry.open_planes[packet.hit.primID[lane]].at(centre_u, centre_v,
                                                                                  packet.ray.tfar[lane])
                                : inf;
        for (ClosedHit& hit : lanes[lane])
          hit.t = (hit.open ? geometry.open_planes : geometry.closed_planes)[hit.prim].at(centre_u, centre_v, hit.t);
        DepthInterval interval = surfaces ? resolve_surfaces_interval(lanes[lane], options_)
                                          : resolve_interval(lanes[lane], open_t, options_);
        if (entry_rule && interval.lower < 1.0f) first_hits[u_start + lane] =
              lanes[lane].front().prim | (lanes[lane].front().open ? kOpenFlag : 0);
        intervals.at(u_start + lane, v) = interval;
        if (interval.lower < 1.0f) ++local.hits;
      }
    }
    if (entry_rule) {
      const auto entry_start = Clock::now();
      entry_row(v);
      local.entry_seconds += seconds_since(entry_start);
    }
  }
  (void)closed_id;
  local.ray_seconds = seconds_since(ray_start) - local.entry_seconds;
  local.rays = uint64_t(size) * size;
  if (stats) stats->add(local);
  return intervals;
}

bool DualDepthRenderer::caps_apply() const {
  // The far-plane comparison rule is measured as its authors have it, uncapped.
  return options_.cap_exits_at_receiver_surfaces && !options_.open_exit_at_far_plane;
}

Result<TileIntervals> DualDepthRenderer::render(TileCoord tile, DualDepthStats* stats, RenderBuffers* buffers) const {
  DualDepthStats local;
  auto intervals = render_centre(tile, &local, buffers);
  if (!intervals) return intervals.error();
  auto cap_start = Clock::now();
  if (caps_apply() && !scene_.triangles_of(tile).empty()) {
    // Cap every exit by the receiver surfaces inside its texel (receiver_surface_caps under
    // `anywhere`, second_layer_caps under `surfaces`).
    std::vector<float> storage = buffers ? std::move(buffers->caps) : std::vector<float>{};
    std::vector<float> caps =
        options_.receivers == ReceiverContract::surfaces
            ? second_layer_caps(scene_, tile, options_.coplanar_epsilon, *intervals, options_.exit_margin,
                                nullptr, std::move(storage), buffers ? &buffers->second_layer : nullptr)
            : receiver_surface_caps(scene_, tile, nullptr, std::move(storage));
    apply_exit_caps(*intervals, caps, options_.exit_margin);
    if (buffers) buffers->caps = std::move(caps);
  }
  local.cap_seconds = seconds_since(cap_start);
  local.exits = 0;
  for (const DepthInterval& interval : intervals->texels) local.exits += interval.upper > interval.lower && interval.lower < 1.0f;
  if (stats) stats->add(local);
  return intervals;
}

void apply_exit_caps(TileIntervals& intervals, std::span<const float> caps, float exit_margin) {
  for (size_t i = 0; i < intervals.texels.size(); ++i) {
    DepthInterval& interval = intervals.texels[i];
    if (interval.upper > interval.lower && interval.lower < 1.0f)
      interval.upper = std::max(interval.lower, std::min(interval.upper, caps[i] - exit_margin));
  }
}

double entry_tolerance_depth(const LightFrame& frame, const WorldBounds& bounds) {
  return frame.depth_from_world(ground_truth_offset(bounds)) + second_layer::kSameSurface;
}

void apply_entry_rule(TileIntervals& intervals) {
  if (intervals.entry_lower.empty()) return;
  for (size_t i = 0; i < intervals.texels.size(); ++i)
    intervals.texels[i].lower = std::min(intervals.texels[i].lower, intervals.entry_lower[i]);
  intervals.entry_lower.clear();
}

}  // namespace shadowtiles
