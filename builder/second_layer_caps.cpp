#include "builder/second_layer_caps.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <span>
#include <utility>

#include "builder/embree_device.hpp"
#include "builder/second_layer_rule.hpp"

namespace shadowtiles {
namespace {

constexpr double kWiden = 1.0 / (1 << 20);  // texels the occluder's edges are widened by
constexpr double kEpsilonShrink = 1.0 - 1.0 / (1 << 20);
constexpr uint32_t kCell = 8;               // texels per grid cell side
constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct Prepared {
  std::array<LightSpacePoint, 3> p;
  double lo_u, hi_u, lo_v, hi_v, zmin, zmax;
  bool edge_on;
  double gu = 0, gv = 0;             // depth per texel along u, v
  std::array<double, 3> A{}, B{}, widen{};  // inward edge k: A (u - p_k.u) + B (v - p_k.v) + widen >= 0

  double depth_at(double u, double v) const { return p[0].depth + gu * (u - p[0].u) + gv * (v - p[0].v); }
};

Prepared prepare(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  Prepared t;
  t.p = {a, b, c};
  t.lo_u = std::min({a.u, b.u, c.u});
  t.hi_u = std::max({a.u, b.u, c.u});
  t.lo_v = std::min({a.v, b.v, c.v});
  t.hi_v = std::max({a.v, b.v, c.v});
  t.zmin = std::min({a.depth, b.depth, c.depth});
  t.zmax = std::max({a.depth, b.depth, c.depth});
  t.edge_on = second_layer::edge_on(a, b, c);
  if (t.edge_on) return t;
  const double bu = b.u - a.u, bv = b.v - a.v, bd = b.depth - a.depth;
  const double cu = c.u - a.u, cv = c.v - a.v, cd = c.depth - a.depth;
  const double nx = bv * cd - bd * cv, ny = bd * cu - bu * cd, nz = bu * cv - bv * cu;
  t.gu = -nx / nz;
  t.gv = -ny / nz;
  const double s = nz > 0 ? 1.0 : -1.0;
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& p = t.p[k];
    const LightSpacePoint& q = t.p[(k + 1) % 3];
    t.A[k] = -s * (q.v - p.v);
    t.B[k] = s * (q.u - p.u);
    t.widen[k] = kWiden * std::hypot(t.A[k], t.B[k]);
  }
  return t;
}

struct Polygon {
  std::array<LightSpacePoint, 24> at;
  unsigned count = 0;
};

// Keeps the part of `in` where the linear function f >= 0 (f given per vertex by `value`).
template <class F>
void clip(const Polygon& in, Polygon& out, F value) {
  out.count = 0;
  std::array<double, 24> f;
  for (unsigned k = 0; k < in.count; ++k) f[k] = value(in.at[k]);
  for (unsigned k = 0; k < in.count && out.count + 2 <= out.at.size(); ++k) {
    const unsigned n = k + 1 == in.count ? 0 : k + 1;
    const LightSpacePoint& p = in.at[k];
    const LightSpacePoint& q = in.at[n];
    if (f[k] >= 0) out.at[out.count++] = p;
    if ((f[k] >= 0) != (f[n] >= 0)) {
      const double t = f[k] / (f[k] - f[n]);
      out.at[out.count++] = {p.u + t * (q.u - p.u), p.v + t * (q.v - p.v), p.depth + t * (q.depth - p.depth)};
    }
  }
}

// The region of `back` lying behind `front` by at least `gap` and, when `most` is finite, by at most
// `most` (widened as the header says), into `region`; false when empty.
bool region_behind(const Prepared& back, const Prepared& front, double gap, double most, Polygon& region) {
  Polygon scratch;
  Polygon* current = &region;
  Polygon* next = &scratch;
  region.count = 3;
  for (int k = 0; k < 3; ++k) region.at[k] = back.p[k];
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& e = front.p[k];
    clip(*current, *next, [&](const LightSpacePoint& x) {
      return front.A[k] * (x.u - e.u) + front.B[k] * (x.v - e.v) + front.widen[k];
    });
    std::swap(current, next);
    if (current->count < 3) return false;
  }
  clip(*current, *next, [&](const LightSpacePoint& x) { return x.depth - front.depth_at(x.u, x.v) - gap; });
  std::swap(current, next);
  if (current->count >= 3 && std::isfinite(most)) {
    clip(*current, *next, [&](const LightSpacePoint& x) { return most - (x.depth - front.depth_at(x.u, x.v)); });
    std::swap(current, next);
  }
  if (current != &region) region = *current;
  return region.count >= 3;
}

// Near cover (second_layer::near_cover_offset): lowers each texel's cap to the shallowest point of
// the convex `region` inside its closed square at or below the texel's floor, lower + `offset`.
// Per texel, exact clipping in double: the square's four sides, then depth >= floor. Texels without
// an exit have nothing to cap.
void lower_caps_above_floor(const Polygon& region, const TexelWindow& window, const TileIntervals& intervals,
                            double offset, std::span<float> cap) {
  double lo_u = region.at[0].u, hi_u = lo_u, lo_v = region.at[0].v, hi_v = lo_v, deepest = region.at[0].depth;
  for (unsigned k = 1; k < region.count; ++k) {
    lo_u = std::min(lo_u, region.at[k].u), hi_u = std::max(hi_u, region.at[k].u);
    lo_v = std::min(lo_v, region.at[k].v), hi_v = std::max(hi_v, region.at[k].v);
    deepest = std::max(deepest, region.at[k].depth);
  }
  const double size = window.size;
  lo_u -= window.u0 + kWiden, hi_u += kWiden - window.u0, lo_v -= window.v0 + kWiden, hi_v += kWiden - window.v0;
  if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) return;
  auto texel = [&](double at) { return uint32_t(std::clamp(std::floor(at), 0.0, size - 1)); };
  const uint32_t i0 = texel(lo_u), i1 = texel(hi_u), j0 = texel(lo_v), j1 = texel(hi_v);
  Polygon a, b;
  for (uint32_t j = j0; j <= j1; ++j)
    for (uint32_t i = i0; i <= i1; ++i) {
      const DepthInterval& interval = intervals.at(i, j);
      if (!(interval.upper > interval.lower && interval.lower < 1.0f)) continue;
      const double floor_depth = double(interval.lower) + offset;
      if (deepest < floor_depth) continue;
      const double su = window.u0 + i, sv = window.v0 + j;
      clip(region, a, [&](const LightSpacePoint& x) { return x.u - su; });
      clip(a, b, [&](const LightSpacePoint& x) { return su + 1 - x.u; });
      clip(b, a, [&](const LightSpacePoint& x) { return x.v - sv; });
      clip(a, b, [&](const LightSpacePoint& x) { return sv + 1 - x.v; });
      clip(b, a, [&](const LightSpacePoint& x) { return x.depth - floor_depth; });
      if (a.count == 0) continue;
      double shallowest = a.at[0].depth;
      for (unsigned k = 1; k < a.count; ++k) shallowest = std::min(shallowest, a.at[k].depth);
      float& slot = cap[size_t(j) * window.size + i];
      slot = std::min(slot, float(shallowest));
    }
}

// Pairs (i < j) of `candidates` whose widened footprint boxes overlap, found by Embree's BVH-BVH
// collision on boxes spanning the whole depth range (so the 3D test is the 2D one).
struct CollideData {
  const std::vector<Prepared>* prepared;
  const std::vector<uint32_t>* candidates;
  double u0, v0;
  std::mutex mutex;
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
};

void candidate_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* data = static_cast<const CollideData*>(args->geometryUserPtr);
  const Prepared& t = (*data->prepared)[(*data->candidates)[args->primID]];
  constexpr float kPad = 1.0f / 256;  // texels: covers the float rounding of tile-local bounds
  RTCBounds* b = args->bounds_o;
  b->lower_x = float(t.lo_u - data->u0) - kPad;
  b->upper_x = float(t.hi_u - data->u0) + kPad;
  b->lower_y = float(t.lo_v - data->v0) - kPad;
  b->upper_y = float(t.hi_v - data->v0) + kPad;
  b->lower_z = 0.0f;
  b->upper_z = 1.0f;
}

void collect_pairs(void* user, RTCCollision* collisions, unsigned count) {
  auto* data = static_cast<CollideData*>(user);
  std::lock_guard lock(data->mutex);
  for (unsigned k = 0; k < count; ++k) {
    const uint32_t a = collisions[k].primID0, b = collisions[k].primID1;
    if (a < b) data->pairs.emplace_back((*data->candidates)[a], (*data->candidates)[b]);
  }
}

std::vector<std::pair<uint32_t, uint32_t>> overlapping_pairs(RTCDevice device, const std::vector<Prepared>& prepared,
                                                             const std::vector<uint32_t>& candidates,
                                                             const TexelWindow& window) {
  if (candidates.size() < 2) return {};
  CollideData data{&prepared, &candidates, window.u0, window.v0, {}, {}};
  EmbreeScene scene(rtcNewScene(device));
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, unsigned(candidates.size()));
  rtcSetGeometryUserData(geometry, &data);
  rtcSetGeometryBoundsFunction(geometry, candidate_bounds, &data);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene.get(), geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene.get());
  rtcCollide(scene.get(), scene.get(), collect_pairs, &data);
  // A self-collision reports each pair from both sides; only (a < b) is kept. (Should one come twice
  // the caps are the same: each region only lowers a minimum.)
  return std::move(data.pairs);
}

}  // namespace

std::vector<float> second_layer_caps(RTCDevice device, const LightSpaceScene& scene, TileCoord tile, double coplanar_epsilon,
                                     const TileIntervals& intervals, float exit_margin, SecondLayerCapCounts* counts) {
  const uint32_t size = scene.layout().tile_size();
  const TexelWindow window{double(tile.x) * size, double(tile.y) * size, size};
  std::vector<float> cap(size_t(size) * size, std::numeric_limits<float>::infinity());
  const Scene& world = scene.scene();
  const auto triangles = scene.triangles_of(tile);
  SecondLayerCapCounts local;

  std::vector<Prepared> prepared;
  prepared.reserve(triangles.size());
  for (uint32_t t : triangles) {
    const auto& tri = world.triangles[t];
    prepared.push_back(prepare(scene.vertex(tri[0]), scene.vertex(tri[1]), scene.vertex(tri[2])));
    if (prepared.back().edge_on)
      lower_caps_by_triangle(prepared.back().p[0], prepared.back().p[1], prepared.back().p[2], window, cap,
                             &local.texels);
  }

  // Cells of kCell texels over the tile: the prune below keeps per cell the largest upper a cap
  // could still lower, in a max pyramid so a box of any size is checked in at most 3x3 entries.
  const uint32_t cells = (size + kCell - 1) / kCell;
  auto cell_of = [&](double texel) {
    return uint32_t(std::clamp(std::floor(texel / kCell), 0.0, double(cells - 1)));
  };
  std::vector<uint32_t> candidates;
  candidates.reserve(prepared.size());
  for (size_t i = 0; i < prepared.size(); ++i) {
    const Prepared& t = prepared[i];
    if (t.edge_on) continue;
    const double lo_u = t.lo_u - kWiden - window.u0, hi_u = t.hi_u + kWiden - window.u0;
    const double lo_v = t.lo_v - kWiden - window.v0, hi_v = t.hi_v + kWiden - window.v0;
    if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) continue;
    candidates.push_back(uint32_t(i));
  }

  // Per cell, the largest upper a cap could still lower (-inf: nothing to cap in the cell).
  const float kNothing = -std::numeric_limits<float>::infinity();
  std::vector<float> cell_upper(size_t(cells) * cells, kNothing);
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      const DepthInterval& t = intervals.at(u, v);
      if (t.upper > t.lower && t.lower < 1.0f) {
        float& slot = cell_upper[size_t(v / kCell) * cells + u / kCell];
        slot = std::max(slot, t.upper);
      }
    }
  std::vector<std::vector<float>> pyramid{std::move(cell_upper)};
  std::vector<uint32_t> sides{cells};
  while (sides.back() > 1) {
    const uint32_t from = sides.back(), to = (from + 1) / 2;
    std::vector<float> level(size_t(to) * to, kNothing);
    const std::vector<float>& fine = pyramid.back();
    for (uint32_t y = 0; y < from; ++y)
      for (uint32_t x = 0; x < from; ++x) {
        float& slot = level[size_t(y / 2) * to + x / 2];
        slot = std::max(slot, fine[size_t(y) * from + x]);
      }
    pyramid.push_back(std::move(level));
    sides.push_back(to);
  }
  // Could a region whose depth is >= `shallowest` change an interval in texels [lo, hi] (global)?
  auto matters = [&](double shallowest, double lo_u, double hi_u, double lo_v, double hi_v) {
    const float capped = float(shallowest) - exit_margin;  // as apply_exit_caps computes it, at the most
    uint32_t x0 = cell_of(lo_u - window.u0), x1 = cell_of(hi_u - window.u0);
    uint32_t y0 = cell_of(lo_v - window.v0), y1 = cell_of(hi_v - window.v0);
    size_t level = 0;
    while (std::max(x1 - x0, y1 - y0) > 2) x0 /= 2, x1 /= 2, y0 /= 2, y1 /= 2, ++level;
    const std::vector<float>& upper = pyramid[level];
    for (uint32_t y = y0; y <= y1; ++y)
      for (uint32_t x = x0; x <= x1; ++x)
        if (capped < upper[size_t(y) * sides[level] + x]) return true;
    return false;
  };

  // Narrowed so the regions found contain the exact ones (the header), the floor lowered likewise.
  const double epsilon = coplanar_epsilon * kEpsilonShrink;
  const double same_surface = second_layer::kSameSurface * kEpsilonShrink;
  const double floor_offset =
      second_layer::near_cover_offset(coplanar_epsilon) - coplanar_epsilon * (1 - kEpsilonShrink);
  Polygon region;
  // Could `region` (every point at least `shallowest` deep) lower a cap? Counts the skip if not.
  auto region_matters = [&](double& shallowest) {
    double lo_u = region.at[0].u, hi_u = lo_u, lo_v = region.at[0].v, hi_v = lo_v;
    shallowest = region.at[0].depth;
    for (unsigned k = 1; k < region.count; ++k) {
      shallowest = std::min(shallowest, region.at[k].depth);
      lo_u = std::min(lo_u, region.at[k].u), hi_u = std::max(hi_u, region.at[k].u);
      lo_v = std::min(lo_v, region.at[k].v), hi_v = std::max(hi_v, region.at[k].v);
    }
    if (matters(shallowest, lo_u - 1, hi_u + 1, lo_v - 1, hi_v + 1)) return true;
    ++local.skipped;
    return false;
  };
  auto lower_by_region = [&](const Prepared& back, const Prepared& front) {
    if (!(back.zmax > front.zmin + same_surface)) return;  // nowhere behind it
    // Every point of either region is at least this deep: behind `front`, and on `back`.
    const double bound = std::max(back.zmin, front.zmin + same_surface);
    if (!matters(bound, std::max(back.lo_u, front.lo_u) - 1, std::min(back.hi_u, front.hi_u) + 1,
                 std::max(back.lo_v, front.lo_v) - 1, std::min(back.hi_v, front.hi_v) + 1)) {
      ++local.skipped;
      return;
    }
    ++local.pairs_tested;
    double shallowest = 0;
    // Behind by epsilon: the second layer wherever it lies.
    if (back.zmax > front.zmin + epsilon && region_behind(back, front, epsilon, kInfinity, region) &&
        region_matters(shallowest)) {
      ++local.regions;
      for (unsigned k = 1; k + 1 < region.count; ++k)
        lower_caps_by_triangle(region.at[0], region.at[k], region.at[k + 1], window, cap, &local.texels);
    }
    // Near cover: behind by less than epsilon, the second layer below each texel's lower + offset.
    if (back.zmin <= front.zmax + epsilon && region_behind(back, front, same_surface, epsilon, region) &&
        region_matters(shallowest)) {
      ++local.near_regions;
      lower_caps_above_floor(region, window, intervals, floor_offset, cap);
    }
  };
  if (pyramid.back()[0] == kNothing) candidates.clear();  // no exit in the tile: nothing to cap
  for (const auto& [i, j] : overlapping_pairs(device, prepared, candidates, window)) {
    lower_by_region(prepared[i], prepared[j]);
    lower_by_region(prepared[j], prepared[i]);
  }
  if (counts) {
    counts->pairs_tested += local.pairs_tested;
    counts->regions += local.regions;
    counts->skipped += local.skipped;
    counts->near_regions += local.near_regions;
    counts->texels.clipped += local.texels.clipped;
    counts->texels.interior += local.texels.interior;
    counts->texels.fallback += local.texels.fallback;
  }
  return cap;
}

}  // namespace shadowtiles
