#include "builder/dual_depth_renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <limits>
#include <vector>

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
};

// Per-geometry data the filter needs: which solid-bounding triangles face the light, and which
// belong to heightfields (solids closed by the far plane).
struct ClosedGeometryData {
  std::vector<uint8_t> front;
  std::vector<uint8_t> heightfield;
  std::vector<float> slack;
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
        {t, prim, data->front[prim] != 0, data->heightfield[prim] != 0, data->slack[prim]});
    args->valid[i] = 0;
  }
}

struct TileGeometry {
  std::vector<float> closed_vertices, open_vertices;    // xyz per vertex, 3 vertices per triangle
  ClosedGeometryData closed;                            // closed meshes and heightfields
  size_t open_count = 0;
};

// Front-facing toward the light: counter-clockwise seen from the light, i.e. the normal's depth
// component is negative (the light travels +depth in a right-handed frame).
bool faces_light(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  return nz <= 0.0;  // edge-on counts as front: the counter then never closes early (conservative)
}

TileGeometry gather_tile_geometry(const LightSpaceScene& scene, TileCoord tile) {
  TileGeometry geometry;
  const double u0 = double(tile.x) * scene.layout().tile_size();
  const double v0 = double(tile.y) * scene.layout().tile_size();
  const Scene& world = scene.scene();
  auto emit = [&](std::vector<float>& out, const LightSpacePoint& p) {
    out.push_back(float(p.u - u0));
    out.push_back(float(p.v - v0));
    out.push_back(float(p.depth));
  };
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    const LightSpacePoint& a = scene.vertex(tri[0]);
    const LightSpacePoint& b = scene.vertex(tri[1]);
    const LightSpacePoint& c = scene.vertex(tri[2]);
    MeshKind kind = world.meshes[world.triangle_mesh[t]].kind;
    if (kind != MeshKind::open) {
      emit(geometry.closed_vertices, a);
      emit(geometry.closed_vertices, b);
      emit(geometry.closed_vertices, c);
      geometry.closed.front.push_back(faces_light(a, b, c) ? 1 : 0);
      geometry.closed.heightfield.push_back(kind == MeshKind::heightfield ? 1 : 0);
      geometry.closed.slack.push_back(exit_slack(a, b, c));
    } else {
      emit(geometry.open_vertices, a);
      emit(geometry.open_vertices, b);
      emit(geometry.open_vertices, c);
      ++geometry.open_count;
    }
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

  DepthInterval interval;  // miss: [1, +inf)
  if (closed_hits.empty() && open_t == std::numeric_limits<float>::infinity()) return interval;
  if (closed_hits.empty() || open_t <= closed_hits.front().t) {
    interval.lower = open_t;
    interval.upper = options.open_exit_at_far_plane ? std::max(open_t, 1.0f) : open_t;
    return interval;
  }
  interval.lower = closed_hits.front().t;
  interval.upper = interval.lower;
  if (!closed_hits.front().front) return interval;
  // The solid is the union of closed meshes and heightfields; a heightfield's solid is closed by
  // the far plane. The ray is inside while the counter is positive.
  int depth = 0, heightfield_depth = 0;
  for (const ClosedHit& hit : closed_hits) {
    depth += hit.front ? 1 : -1;
    if (hit.heightfield) heightfield_depth += hit.front ? 1 : -1;
    if (depth < 0) return interval;  // inconsistent: stay conservative
    if (depth == 0) {
      interval.upper = std::max(interval.lower, hit.t - exit_margin - hit.slack);
      return interval;
    }
  }
  // Still inside: only a heightfield (solid down to the far plane) with no open surface below
  // gives an exit, the far plane.
  if (heightfield_depth > 0 && open_t == std::numeric_limits<float>::infinity())
    interval.upper = std::max(interval.lower, 1.0f);
  return interval;
}

// Receivers lie anywhere in a texel, not only on its centre's ray: near a silhouette or a crease, a
// shadowed surface other than the centre ray's exit triangle can sit, within the texel, at a depth
// between the centre ray's entry and exit (the back of a bust just inside its outline, the far slope
// of a ridge at a grazing sun). Such a receiver must stay shadowed, so each texel's exit is capped by
// the shallowest depth, within the texel's square, of every surface a shadowed receiver can lie on:
// closed or heightfield triangles facing away from the light (or edge-on), and open triangles. That
// depth is exact: the triangle is clipped to the square and depth, linear on it, is smallest at a
// vertex of the clipped polygon. Computed in the scene's double light-space coordinates (global
// texels) so the result does not depend on the tiling. Returns the cap per texel of the tile
// (+inf where nothing limits it).
struct ClipVertex {
  double u, v, depth;
};

// Sutherland-Hodgman against one axis-aligned edge: keeps the side where sign * (coord - bound) >= 0.
void clip_polygon(std::vector<ClipVertex>& polygon, std::vector<ClipVertex>& scratch, bool along_u, double bound,
                  double sign) {
  scratch.clear();
  const size_t n = polygon.size();
  for (size_t k = 0; k < n; ++k) {
    const ClipVertex& p = polygon[k];
    const ClipVertex& q = polygon[(k + 1) % n];
    const double dp = sign * ((along_u ? p.u : p.v) - bound), dq = sign * ((along_u ? q.u : q.v) - bound);
    if (dp >= 0) scratch.push_back(p);
    if ((dp >= 0) != (dq >= 0)) {
      const double t = dp / (dp - dq);
      scratch.push_back({p.u + t * (q.u - p.u), p.v + t * (q.v - p.v), p.depth + t * (q.depth - p.depth)});
    }
  }
  polygon.swap(scratch);
}

std::vector<float> receiver_surface_caps(const LightSpaceScene& scene, TileCoord tile) {
  const uint32_t size = scene.layout().tile_size();
  const double u0 = double(tile.x) * size, v0 = double(tile.y) * size;
  std::vector<float> cap(size_t(size) * size, std::numeric_limits<float>::infinity());
  const Scene& world = scene.scene();
  std::vector<ClipVertex> polygon, scratch;
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    const LightSpacePoint& a = scene.vertex(tri[0]);
    const LightSpacePoint& b = scene.vertex(tri[1]);
    const LightSpacePoint& c = scene.vertex(tri[2]);
    const MeshKind kind = world.meshes[world.triangle_mesh[t]].kind;
    const double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
    if (kind != MeshKind::open && nz < 0) continue;  // faces the light: an entry surface, the lit side
    const double lo_u = std::min({a.u, b.u, c.u}) - u0, hi_u = std::max({a.u, b.u, c.u}) - u0;
    const double lo_v = std::min({a.v, b.v, c.v}) - v0, hi_v = std::max({a.v, b.v, c.v}) - v0;
    if (hi_u < 0 || hi_v < 0 || lo_u >= size || lo_v >= size) continue;
    const uint32_t i0 = uint32_t(std::max(0.0, std::floor(lo_u))), i1 = uint32_t(std::min(size - 1.0, std::floor(hi_u)));
    const uint32_t j0 = uint32_t(std::max(0.0, std::floor(lo_v))), j1 = uint32_t(std::min(size - 1.0, std::floor(hi_v)));
    for (uint32_t j = j0; j <= j1; ++j)
      for (uint32_t i = i0; i <= i1; ++i) {
        const double su = u0 + i, sv = v0 + j;  // the texel's square [su, su+1] x [sv, sv+1]
        polygon = {{a.u, a.v, a.depth}, {b.u, b.v, b.depth}, {c.u, c.v, c.depth}};
        clip_polygon(polygon, scratch, true, su, 1);
        if (!polygon.empty()) clip_polygon(polygon, scratch, true, su + 1, -1);
        if (!polygon.empty()) clip_polygon(polygon, scratch, false, sv, 1);
        if (!polygon.empty()) clip_polygon(polygon, scratch, false, sv + 1, -1);
        if (polygon.empty()) continue;
        double shallowest = polygon.front().depth;
        for (const ClipVertex& p : polygon) shallowest = std::min(shallowest, p.depth);
        float& slot = cap[size_t(j) * size + i];
        slot = std::min(slot, float(shallowest));
      }
  }
  return cap;
}

}  // namespace

void DualDepthStats::add(const DualDepthStats& other) {
  rays += other.rays;
  hits += other.hits;
  exits += other.exits;
  triangles += other.triangles;
  bvh_seconds += other.bvh_seconds;
  ray_seconds += other.ray_seconds;
}

DualDepthRenderer::DualDepthRenderer(const EmbreeDevice& device, const LightSpaceScene& scene,
                                     DualDepthOptions options)
    : device_(device), scene_(scene), options_(options) {}

Result<TileIntervals> DualDepthRenderer::render(TileCoord tile, DualDepthStats* stats) const {
  const uint32_t size = scene_.layout().tile_size();
  TileIntervals intervals;
  intervals.size = size;
  intervals.texels.assign(size_t(size) * size, DepthInterval{});
  DualDepthStats local;
  if (!scene_.layout().contains(tile))
    return make_error(ErrorCode::invalid_input, "tile outside the map");
  if (scene_.triangles_of(tile).empty()) {
    if (stats) stats->add(local);
    return intervals;
  }

  auto bvh_start = Clock::now();
  TileGeometry geometry = gather_tile_geometry(scene_, tile);
  EmbreeScene rtc_scene(rtcNewScene(device_.get()));
  rtcSetSceneFlags(rtc_scene.get(), RTC_SCENE_FLAG_ROBUST);
  unsigned closed_id = RTC_INVALID_GEOMETRY_ID;
  if (!geometry.closed.front.empty())
    closed_id = attach_triangles(device_.get(), rtc_scene.get(), geometry.closed_vertices, &geometry.closed);
  unsigned open_id = RTC_INVALID_GEOMETRY_ID;
  if (geometry.open_count)
    open_id = attach_triangles(device_.get(), rtc_scene.get(), geometry.open_vertices, nullptr);
  rtcCommitScene(rtc_scene.get());
  if (RTCError error = rtcGetDeviceError(device_.get()); error != RTC_ERROR_NONE)
    return make_error(ErrorCode::io_error, "embree failed to build the tile BVH (error " +
                                               std::to_string(int(error)) + ")");
  local.triangles = geometry.closed.front.size() + geometry.open_count;
  local.bvh_seconds = seconds_since(bvh_start);

  auto ray_start = Clock::now();
  std::array<std::vector<ClosedHit>, kPacket> lanes;
  CollectContext context;
  rtcInitIntersectContext(&context.base);
  context.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  context.lanes = &lanes;
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[kPacket];
  const float inf = std::numeric_limits<float>::infinity();
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
        bool open_hit = packet.hit.geomID[lane] == open_id && open_id != RTC_INVALID_GEOMETRY_ID;
        float open_t = open_hit ? packet.ray.tfar[lane] : inf;
        DepthInterval interval = resolve_interval(lanes[lane], open_t, options_);
        intervals.at(u_start + lane, v) = interval;
        if (interval.lower < 1.0f) ++local.hits;
      }
    }
  }
  (void)closed_id;
  // Cap every exit by the receiver surfaces inside its texel (see receiver_surface_caps); the
  // far-plane comparison rule is measured as its authors have it, uncapped.
  const bool capped = options_.cap_exits_at_receiver_surfaces && !options_.open_exit_at_far_plane;
  const std::vector<float> caps = capped ? receiver_surface_caps(scene_, tile)
                                         : std::vector<float>(intervals.texels.size(), std::numeric_limits<float>::infinity());
  local.exits = 0;
  for (size_t i = 0; i < intervals.texels.size(); ++i) {
    DepthInterval& interval = intervals.texels[i];
    if (interval.upper > interval.lower && interval.lower < 1.0f) {
      interval.upper = std::max(interval.lower, std::min(interval.upper, caps[i] - options_.exit_margin));
      local.exits += interval.upper > interval.lower;
    }
  }
  local.rays = uint64_t(size) * size;
  local.ray_seconds = seconds_since(ray_start);
  if (stats) stats->add(local);
  return intervals;
}

}  // namespace shadowtiles
