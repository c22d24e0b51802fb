#include "builder/dual_depth_renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <limits>
#include <vector>

#include "builder/entry_cover.hpp"
#include "builder/entry_depth_gap.hpp"
#include "builder/receiver_surface_caps.hpp"
#include "builder/tile_geometry.hpp"
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
  caps.add(other.caps);
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
  if (entry_rule) {  // the entry rule's own geometry (mesh neighbours), timed as its work
    const auto entry_start = Clock::now();
    link_tile_neighbours(scene_, geometry);
    local.entry_seconds += seconds_since(entry_start);
  }

  const double entry_before_rays = local.entry_seconds;
  auto ray_start = Clock::now();
  // The entry rule's: a band of rows' first-hit triangles, primitive id with the open set's flag. The
  // entry pass runs once per band of kEntryBand rows rather than per row, so the rays between rows
  // do not evict a vertex's fan between its searches on consecutive rows.
  constexpr uint32_t kOpenFlag = EntryCover::kOpenFlag;
  constexpr uint32_t kEntryBand = 16;
  std::vector<uint32_t> first_hits(entry_rule ? size_t(size) * kEntryBand : 0);
  std::array<std::vector<ClosedHit>, kPacket> lanes;
  CollectContext context;
  rtcInitIntersectContext(&context.base);
  context.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  context.lanes = &lanes;
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[kPacket];
  const float inf = std::numeric_limits<float>::infinity();
  const uint64_t tile_u0 = uint64_t(tile.x) * size, tile_v0 = uint64_t(tile.y) * size;
  // The entry rule's pass, row by row over a band of rows after their rays, timed apart from them.
  EntryCover entry_cover(geometry, tile, size, options_.entry_slack, options_.entry_tolerance);
  std::vector<uint32_t> gap_candidates;  // texels no cover lowered that the depth gap may (row-major)
  auto entry_row = [&](uint32_t v) {
    const size_t row = size_t(v) * size;
    const std::span<const uint32_t> row_hits = std::span(first_hits).subspan(size_t(v % kEntryBand) * size, size);
    entry_cover.bound_row(v, row_hits, std::span(intervals.texels).subspan(row, size),
                          std::span(intervals.entry_lower).subspan(row, size));
    for (uint32_t u = 0; u < size; ++u) {
      const size_t i = row + u;
      const float lower = intervals.texels[i].lower;
      if (lower >= 1.0f) continue;
      const bool open = (row_hits[u] & kOpenFlag) != 0;
      const uint32_t prim = row_hits[u] & ~kOpenFlag;
      if (intervals.entry_lower[i] >= lower &&
          gap_may_lower((open ? geometry.open_planes : geometry.closed_planes)[prim], double(tile_u0) + u + 0.5,
                        double(tile_v0) + v + 0.5, lower, options_.entry_slack, options_.entry_tolerance))
        gap_candidates.push_back(uint32_t(i));
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
        if (entry_rule && interval.lower < 1.0f) first_hits[size_t(v % kEntryBand) * size + u_start + lane] =
              lanes[lane].front().prim | (lanes[lane].front().open ? kOpenFlag : 0);
        intervals.at(u_start + lane, v) = interval;
        if (interval.lower < 1.0f) ++local.hits;
      }
    }
    if (entry_rule && (v % kEntryBand == kEntryBand - 1 || v + 1 == size)) {
      const auto entry_start = Clock::now();
      for (uint32_t band_row = v - v % kEntryBand; band_row <= v; ++band_row) entry_row(band_row);
      local.entry_seconds += seconds_since(entry_start);
    }
  }
  if (entry_rule) {  // the depth-gap bound, for the texels no cover lowered
    const auto entry_start = Clock::now();
    lower_entry_bounds_by_depth_gaps(geometry, tile, size, intervals.texels, gap_candidates, intervals.entry_lower,
                                     options_.exit_margin, options_.entry_slack, options_.entry_tolerance);
    local.entry_seconds += seconds_since(entry_start);
  }
  (void)closed_id;
  local.ray_seconds = seconds_since(ray_start) - (local.entry_seconds - entry_before_rays);
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
                                &local.caps, std::move(storage), buffers ? &buffers->second_layer : nullptr)
            : receiver_surface_caps(scene_, tile, &local.caps.texels, std::move(storage), &*intervals);
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
    if (takes_exit_cap(interval))
      interval.upper = std::max(interval.lower, std::min(interval.upper, caps[i] - exit_margin));
  }
}

double entry_tolerance_depth(const LightFrame& frame, const WorldBounds& bounds) {
  return frame.depth_from_world(ground_truth_offset(bounds)) + second_layer::kSameSurface;
}

}  // namespace shadowtiles
