#include "builder/reference_entry_bounds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/float_rounding.hpp"

namespace shadowtiles {
namespace {

struct Point2 {
  double u, v;
};
using Polygon = std::vector<Point2>;

// Pieces of the remainder smaller than this (texels squared) count as covered: slivers of rounding
// along edges two triangles share.
constexpr double kSliverArea = 1e-9;
constexpr size_t kMaxPieces = 256;  // more: the square counts as not covered (its bound stays the first hit)

double cross(const Point2& a, const Point2& b, const Point2& p) {
  return (b.u - a.u) * (p.v - a.v) - (b.v - a.v) * (p.u - a.u);
}

double area(const Polygon& polygon) {
  double twice = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Point2 &p = polygon[i], &q = polygon[(i + 1) % polygon.size()];
    twice += p.u * q.v - q.u * p.v;
  }
  return std::fabs(twice) / 2;
}

// The part of a convex polygon on the left of a -> b (`left`), or on its right, edges included.
Polygon clip(const Polygon& polygon, const Point2& a, const Point2& b, bool left) {
  Polygon out;
  const double sign = left ? 1.0 : -1.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Point2 &p = polygon[i], &q = polygon[(i + 1) % polygon.size()];
    const double sp = sign * cross(a, b, p), sq = sign * cross(a, b, q);
    if (sp >= 0) out.push_back(p);
    if ((sp > 0 && sq < 0) || (sp < 0 && sq > 0)) {
      const double f = sp / (sp - sq);
      out.push_back({p.u + f * (q.u - p.u), p.v + f * (q.v - p.v)});
    }
  }
  return out;
}

// A triangle of the tile: its footprint counter-clockwise in tile-local texels, and its depths.
struct Footprint {
  std::array<Point2, 3> corner;
  std::array<double, 3> depth;
  double area2;  // twice the signed area (positive: counter-clockwise)

  double depth_at(const Point2& p) const {
    const double wa = cross(corner[1], corner[2], p) / area2;
    const double wb = cross(corner[2], corner[0], p) / area2;
    const double wc = cross(corner[0], corner[1], p) / area2;
    return wa * depth[0] + wb * depth[1] + wc * depth[2];
  }
};

// The convex pieces of `polygon` outside the triangle.
void subtract(const Polygon& polygon, const Footprint& t, std::vector<Polygon>& out) {
  Polygon inside = polygon;
  for (int k = 0; k < 3 && inside.size() >= 3; ++k) {
    const Point2 &a = t.corner[size_t(k)], &b = t.corner[size_t((k + 1) % 3)];
    Polygon outside = clip(inside, a, b, false);
    if (outside.size() >= 3 && area(outside) > kSliverArea) out.push_back(std::move(outside));
    inside = clip(inside, a, b, true);
  }
}

// The largest depth of a triangle over its part of the square; -inf when that part has no area.
double deepest_over(const Footprint& t, const Polygon& square) {
  Polygon part = square;
  for (int k = 0; k < 3 && part.size() >= 3; ++k) part = clip(part, t.corner[size_t(k)], t.corner[size_t((k + 1) % 3)], true);
  if (part.size() < 3 || area(part) <= 0) return -std::numeric_limits<double>::infinity();
  double deepest = -std::numeric_limits<double>::infinity();
  for (const Point2& p : part) deepest = std::max(deepest, t.depth_at(p));
  return deepest;
}

}  // namespace

std::vector<float> reference_entry_bounds(const LightSpaceScene& scene, TileCoord tile, const TileIntervals& first_hits,
                                          double slack, double tolerance) {
  const uint32_t size = first_hits.size;
  const double u0 = double(tile.x) * scene.layout().tile_size(), v0 = double(tile.y) * scene.layout().tile_size();
  const Scene& world = scene.scene();
  // Footprints (edge-on triangles cover nothing), and bins of 16x16 texels listing the footprints whose
  // bounding box meets them.
  std::vector<Footprint> footprints;
  for (uint32_t t : scene.triangles_of(tile)) {
    Footprint f;
    for (int k = 0; k < 3; ++k) {
      const LightSpacePoint& p = scene.vertex(world.triangles[t][size_t(k)]);
      f.corner[size_t(k)] = {p.u - u0, p.v - v0};
      f.depth[size_t(k)] = p.depth;
    }
    f.area2 = cross(f.corner[0], f.corner[1], f.corner[2]);
    if (f.area2 == 0) continue;
    if (f.area2 < 0) {
      std::swap(f.corner[1], f.corner[2]);
      std::swap(f.depth[1], f.depth[2]);
      f.area2 = -f.area2;
    }
    footprints.push_back(f);
  }
  constexpr uint32_t kBin = 16;
  const uint32_t bins = (size + kBin - 1) / kBin;
  std::vector<std::vector<uint32_t>> binned(size_t(bins) * bins);
  for (uint32_t i = 0; i < footprints.size(); ++i) {
    const auto& c = footprints[i].corner;
    auto bin_range = [&](double lo, double hi, uint32_t* first, uint32_t* last) {
      if (hi < 0 || lo > double(size)) return false;
      *first = uint32_t(std::clamp(std::floor(lo / kBin), 0.0, double(bins - 1)));
      *last = uint32_t(std::clamp(std::floor(hi / kBin), 0.0, double(bins - 1)));
      return true;
    };
    uint32_t bu0, bu1, bv0, bv1;
    if (!bin_range(std::min({c[0].u, c[1].u, c[2].u}), std::max({c[0].u, c[1].u, c[2].u}), &bu0, &bu1) ||
        !bin_range(std::min({c[0].v, c[1].v, c[2].v}), std::max({c[0].v, c[1].v, c[2].v}), &bv0, &bv1))
      continue;
    for (uint32_t bv = bv0; bv <= bv1; ++bv)
      for (uint32_t bu = bu0; bu <= bu1; ++bu) binned[size_t(bv) * bins + bu].push_back(i);
  }

  std::vector<float> bounds(first_hits.texels.size());
  std::vector<std::pair<double, uint32_t>> candidates;  // (deepest over the square, footprint)
  std::vector<Polygon> remainder, next;
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      const size_t i = size_t(v) * size + u;
      const float first = first_hits.texels[i].lower;
      bounds[i] = first;
      if (first >= 1.0f) continue;
      const Polygon square{{double(u), double(v)}, {u + 1.0, double(v)}, {u + 1.0, v + 1.0}, {double(u), v + 1.0}};
      candidates.clear();
      for (uint32_t f : binned[size_t(v / kBin) * bins + u / kBin]) {
        const double deepest = deepest_over(footprints[f], square);
        if (deepest > -std::numeric_limits<double>::infinity()) candidates.push_back({deepest, f});
      }
      std::sort(candidates.begin(), candidates.end());
      // The smallest depth B such that the triangles no deeper than B over the square cover it.
      remainder.assign(1, square);
      double cover_depth = std::numeric_limits<double>::infinity();
      for (const auto& [deepest, f] : candidates) {
        next.clear();
        for (const Polygon& piece : remainder) subtract(piece, footprints[f], next);
        remainder.swap(next);
        if (remainder.empty()) {
          cover_depth = deepest;
          break;
        }
        if (remainder.size() > kMaxPieces) break;
      }
      if (cover_depth == std::numeric_limits<double>::infinity()) continue;
      const double entry = cover_depth + tolerance - slack;
      if (entry >= double(first)) continue;
      bounds[i] = std::max(0.0f, float_at_least(entry));
    }
  return bounds;
}

}  // namespace shadowtiles
