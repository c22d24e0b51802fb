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

// The part of `back` inside `front`'s footprint (its edges widened as the header says), into
// `covered`; false when empty.
bool covered_by(const Prepared& back, const Prepared& front, Polygon& covered) {
  Polygon scratch;
  Polygon* current = &covered;
  Polygon* next = &scratch;
  covered.count = 3;
  for (int k = 0; k < 3; ++k) covered.at[k] = back.p[k];
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& e = front.p[k];
    clip(*current, *next, [&](const LightSpacePoint& x) {
      return front.A[k] * (x.u - e.u) + front.B[k] * (x.v - e.v) + front.widen[k];
    });
    std::swap(current, next);
    if (current->count < 3) return false;
  }
  if (current != &covered) covered = *current;
  return true;
}

// The part of `covered` (on `back`, inside `front`'s footprint) lying behind `front` by at least
// `gap` and, when `most` is finite, by at most `most`, into `region`; false when empty.
bool region_behind(const Polygon& covered, const Prepared& front, double gap, double most, Polygon& region) {
  clip(covered, region, [&](const LightSpacePoint& x) { return x.depth - front.depth_at(x.u, x.v) - gap; });
  if (region.count >= 3 && std::isfinite(most)) {
    Polygon scratch;
    clip(region, scratch, [&](const LightSpacePoint& x) { return most - (x.depth - front.depth_at(x.u, x.v)); });
    region = scratch;
  }
  return region.count >= 3;
}

// Near cover (second_layer::near_cover_offset): lowers each texel's cap to the shallowest point of
// the convex `region` inside its closed square at or below the texel's floor, lower + `offset`.
// Per texel, exact clipping in double: the square's four sides, then depth >= floor. Texels without
// an exit have nothing to cap, and texels where no point of the region at or below the floor could
// change the capped interval (its bound, max(floor, shallowest), is not below the cap so far, or
// float(bound) - margin >= upper, as apply_exit_caps computes it) are skipped: the result is exact
// where it matters, like the pruned regions above.
void lower_caps_above_floor(const Polygon& region, const TexelWindow& window, const TileIntervals& intervals,
                            double offset, float exit_margin, std::span<float> cap) {
  double lo_u = region.at[0].u, hi_u = lo_u, lo_v = region.at[0].v, hi_v = lo_v, deepest = region.at[0].depth;
  double shallowest = deepest;
  for (unsigned k = 1; k < region.count; ++k) {
    lo_u = std::min(lo_u, region.at[k].u), hi_u = std::max(hi_u, region.at[k].u);
    lo_v = std::min(lo_v, region.at[k].v), hi_v = std::max(hi_v, region.at[k].v);
    deepest = std::max(deepest, region.at[k].depth);
    shallowest = std::min(shallowest, region.at[k].depth);
  }
  const double size = window.size;
  lo_u -= window.u0 + kWiden, hi_u += kWiden - window.u0, lo_v -= window.v0 + kWiden, hi_v += kWiden - window.v0;
  if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) return;
  auto texel = [&](double at) { return uint32_t(std::clamp(std::floor(at), 0.0, size - 1)); };
  const uint32_t i0 = texel(lo_u), i1 = texel(hi_u), j0 = texel(lo_v), j1 = texel(hi_v);
  Polygon a, b;
  for (uint32_t j = j0; j <= j1; ++j) {
    // Only the texels the region reaches in this row (near-cover regions are thin strips along folds,
    // their boxes mostly empty): its u-extent within the row's band, widened like the box.
    const double band_lo = window.v0 + j - kWiden, band_hi = window.v0 + j + 1 + kWiden;
    double row_lo = std::numeric_limits<double>::infinity(), row_hi = -row_lo;
    for (unsigned k = 0; k < region.count; ++k) {
      const LightSpacePoint& p = region.at[k];
      const LightSpacePoint& q = region.at[k + 1 == region.count ? 0 : k + 1];
      if (p.v >= band_lo && p.v <= band_hi) row_lo = std::min(row_lo, p.u), row_hi = std::max(row_hi, p.u);
      for (double y : {band_lo, band_hi})
        if ((p.v < y) != (q.v < y)) {
          const double u = p.u + (y - p.v) / (q.v - p.v) * (q.u - p.u);
          row_lo = std::min(row_lo, u), row_hi = std::max(row_hi, u);
        }
    }
    if (!(row_lo <= row_hi)) continue;
    const uint32_t first = std::max(i0, texel(row_lo - window.u0 - kWiden));
    const uint32_t last = std::min(i1, texel(row_hi - window.u0 + kWiden));
    for (uint32_t i = first; i <= last; ++i) {
      const DepthInterval& interval = intervals.at(i, j);
      if (!(interval.upper > interval.lower && interval.lower < 1.0f)) continue;
      const double floor_depth = double(interval.lower) + offset;
      if (deepest < floor_depth) continue;
      float& slot = cap[size_t(j) * window.size + i];
      const double bound = std::max(floor_depth, shallowest);
      if (!(bound < slot) || float(bound) - exit_margin >= interval.upper) continue;
      const double su = window.u0 + i, sv = window.v0 + j;
      clip(region, a, [&](const LightSpacePoint& x) { return x.u - su; });
      clip(a, b, [&](const LightSpacePoint& x) { return su + 1 - x.u; });
      clip(b, a, [&](const LightSpacePoint& x) { return x.v - sv; });
      clip(a, b, [&](const LightSpacePoint& x) { return sv + 1 - x.v; });
      clip(b, a, [&](const LightSpacePoint& x) { return x.depth - floor_depth; });
      if (a.count == 0) continue;
      double lowest = a.at[0].depth;
      for (unsigned k = 1; k < a.count; ++k) lowest = std::min(lowest, a.at[k].depth);
      slot = std::min(slot, float(lowest));
    }
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
                                     const TileIntervals& intervals, float exit_margin, SecondLayerCapCounts* counts,
                                     std::vector<float> storage) {
  const uint32_t size = scene.layout().tile_size();
  const TexelWindow window{double(tile.x) * size, double(tile.y) * size, size};
  std::vector<float> cap = std::move(storage);
  cap.assign(size_t(size) * size, std::numeric_limits<float>::infinity());
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
  // Per cell, the smallest lower among texels with an exit (+inf: none), for the near-cover floor.
  const float kNone = std::numeric_limits<float>::infinity();
  std::vector<float> cell_upper(size_t(cells) * cells, kNothing), cell_lower(size_t(cells) * cells, kNone);
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      const DepthInterval& t = intervals.at(u, v);
      if (t.upper > t.lower && t.lower < 1.0f) {
        const size_t cell = size_t(v / kCell) * cells + u / kCell;
        cell_upper[cell] = std::max(cell_upper[cell], t.upper);
        cell_lower[cell] = std::min(cell_lower[cell], t.lower);
      }
    }
  std::vector<std::vector<float>> pyramid{std::move(cell_upper)}, lower_pyramid{std::move(cell_lower)};
  std::vector<uint32_t> sides{cells};
  while (sides.back() > 1) {
    const uint32_t from = sides.back(), to = (from + 1) / 2;
    std::vector<float> level(size_t(to) * to, kNothing), lower_level(size_t(to) * to, kNone);
    const std::vector<float>& fine = pyramid.back();
    const std::vector<float>& fine_lower = lower_pyramid.back();
    for (uint32_t y = 0; y < from; ++y)
      for (uint32_t x = 0; x < from; ++x) {
        const size_t at = size_t(y / 2) * to + x / 2;
        level[at] = std::max(level[at], fine[size_t(y) * from + x]);
        lower_level[at] = std::min(lower_level[at], fine_lower[size_t(y) * from + x]);
      }
    pyramid.push_back(std::move(level));
    lower_pyramid.push_back(std::move(lower_level));
    sides.push_back(to);
  }
  // The smallest lower of a texel with an exit in texels [lo, hi] (global), a bound from its cells.
  auto smallest_lower = [&](double lo_u, double hi_u, double lo_v, double hi_v) {
    uint32_t x0 = cell_of(lo_u - window.u0), x1 = cell_of(hi_u - window.u0);
    uint32_t y0 = cell_of(lo_v - window.v0), y1 = cell_of(hi_v - window.v0);
    size_t level = 0;
    while (std::max(x1 - x0, y1 - y0) > 2) x0 /= 2, x1 /= 2, y0 /= 2, y1 /= 2, ++level;
    float lowest = kNone;
    for (uint32_t y = y0; y <= y1; ++y)
      for (uint32_t x = x0; x <= x1; ++x) lowest = std::min(lowest, lower_pyramid[level][size_t(y) * sides[level] + x]);
    return lowest;
  };
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
  Polygon covered, region;
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
    // Near cover needs a point of `back` at or below some texel's floor in the pair's box.
    const bool behind_by_epsilon = back.zmax > front.zmin + epsilon;
    const bool near = back.zmin <= front.zmax + epsilon &&
                      back.zmax >= double(smallest_lower(std::max(back.lo_u, front.lo_u) - 1,
                                                         std::min(back.hi_u, front.hi_u) + 1,
                                                         std::max(back.lo_v, front.lo_v) - 1,
                                                         std::min(back.hi_v, front.hi_v) + 1)) + floor_offset;
    if (!behind_by_epsilon && !near) {
      ++local.skipped;
      return;
    }
    ++local.pairs_tested;
    double shallowest = 0;
    if (!covered_by(back, front, covered)) return;
    // Behind by epsilon: the second layer wherever it lies.
    if (behind_by_epsilon && region_behind(covered, front, epsilon, kInfinity, region) &&
        region_matters(shallowest)) {
      ++local.regions;
      for (unsigned k = 1; k + 1 < region.count; ++k)
        lower_caps_by_triangle(region.at[0], region.at[k], region.at[k + 1], window, cap, &local.texels);
    }
    // Near cover: behind by less than epsilon, the second layer below each texel's lower + offset.
    if (near && region_behind(covered, front, same_surface, epsilon, region) &&
        region_matters(shallowest)) {
      ++local.near_regions;
      lower_caps_above_floor(region, window, intervals, floor_offset, exit_margin, cap);
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
