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
constexpr size_t kIncrementalPieces = 64;  // more: the depth-order pass hands over to bisection
constexpr size_t kMaxPieces = 4096;  // more in a bisection step: that prefix counts as not covering

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
  double area2;  // twice the signed area (positive: counter-clockwise); 0: edge-on

  double depth_at(const Point2& p) const {
    const double wa = cross(corner[1], corner[2], p) / area2;
    const double wb = cross(corner[2], corner[0], p) / area2;
    const double wc = cross(corner[0], corner[1], p) / area2;
    return wa * depth[0] + wb * depth[1] + wc * depth[2];
  }
};

// The convex pieces of `polygon` outside the triangle. A polygon wholly outside one of its edges is
// kept whole: cutting it along the triangle's edge lines would split it into pieces that still cover
// the same area (on a dense tile the remainder then fragmented past any bound and the square read
// as not covered; honolulu 4096^2 had 552 texels whose bound the build proved and this could not).
void subtract(const Polygon& polygon, const Footprint& t, std::vector<Polygon>& out) {
  for (int k = 0; k < 3; ++k) {
    const Point2 &a = t.corner[size_t(k)], &b = t.corner[size_t((k + 1) % 3)];
    if (std::all_of(polygon.begin(), polygon.end(), [&](const Point2& p) { return cross(a, b, p) <= 0; })) {
      out.push_back(polygon);
      return;
    }
  }
  Polygon inside = polygon;
  for (int k = 0; k < 3 && inside.size() >= 3; ++k) {
    const Point2 &a = t.corner[size_t(k)], &b = t.corner[size_t((k + 1) % 3)];
    Polygon outside = clip(inside, a, b, false);
    if (outside.size() >= 3 && area(outside) > kSliverArea) out.push_back(std::move(outside));
    inside = clip(inside, a, b, true);
  }
}

// `remainder` less the triangle, piece by piece (`next`: working space).
void subtract_from(std::vector<Polygon>& remainder, const Footprint& t, std::vector<Polygon>& next) {
  next.clear();
  for (const Polygon& piece : remainder) subtract(piece, t, next);
  remainder.swap(next);
}

// A triangle over the square: the largest depth of its part there (-inf when that part has no
// area) and the part's area.
struct OverSquare {
  double deepest = -std::numeric_limits<double>::infinity();
  double shallowest = std::numeric_limits<double>::infinity();
  double area = 0;
};
OverSquare over_square(const Footprint& t, const Polygon& square) {
  OverSquare over;
  if (t.area2 == 0) {  // edge-on: no area; where its footprint's box meets the square, its vertices' range
    const double u_lo = std::min({t.corner[0].u, t.corner[1].u, t.corner[2].u});
    const double u_hi = std::max({t.corner[0].u, t.corner[1].u, t.corner[2].u});
    const double v_lo = std::min({t.corner[0].v, t.corner[1].v, t.corner[2].v});
    const double v_hi = std::max({t.corner[0].v, t.corner[1].v, t.corner[2].v});
    if (u_hi < square[0].u || u_lo >= square[2].u || v_hi < square[0].v || v_lo >= square[2].v) return over;
    over.deepest = std::max({t.depth[0], t.depth[1], t.depth[2]});
    over.shallowest = std::min({t.depth[0], t.depth[1], t.depth[2]});
    return over;
  }
  Polygon part = square;
  for (int k = 0; k < 3 && part.size() >= 3; ++k) part = clip(part, t.corner[size_t(k)], t.corner[size_t((k + 1) % 3)], true);
  if (part.size() < 3) return over;
  over.area = area(part);
  if (over.area <= 0) return over;
  for (const Point2& p : part) {
    over.deepest = std::max(over.deepest, t.depth_at(p));
    over.shallowest = std::min(over.shallowest, t.depth_at(p));
  }
  return over;
}

struct Candidate {
  double deepest;  // over the square
  double area;     // of its part of the square
  uint32_t footprint;
};

// Whether `chosen` cover the square (its remainder: nothing but slivers). The largest parts go first,
// so that a few large triangles leave little for many small ones to cut up; false (not covered, so
// the bound stays the first hit) when the remainder still splits into more than kMaxPieces pieces.
bool covers(std::vector<Candidate>& chosen, const std::vector<Footprint>& footprints, const Polygon& square,
            std::vector<Polygon>& remainder, std::vector<Polygon>& next) {
  std::sort(chosen.begin(), chosen.end(), [](const Candidate& a, const Candidate& b) { return a.area > b.area; });
  remainder.assign(1, square);
  for (const Candidate& c : chosen) {
    subtract_from(remainder, footprints[c.footprint], next);
    if (remainder.empty()) return true;
    if (remainder.size() > kMaxPieces) return false;
  }
  return false;
}

}  // namespace

std::vector<float> reference_entry_bounds(const LightSpaceScene& scene, TileCoord tile, const TileIntervals& first_hits,
                                          double slack, double tolerance, double gap) {
  const uint32_t size = first_hits.size;
  const double u0 = double(tile.x) * scene.layout().tile_size(), v0 = double(tile.y) * scene.layout().tile_size();
  const Scene& world = scene.scene();
  // Footprints (edge-on ones cover nothing, but count for the depth gap), and bins of 16x16 texels
  // listing the footprints whose bounding box meets them.
  std::vector<Footprint> footprints;
  for (uint32_t t : scene.triangles_of(tile)) {
    Footprint f;
    for (int k = 0; k < 3; ++k) {
      const LightSpacePoint& p = scene.vertex(world.triangles[t][size_t(k)]);
      f.corner[size_t(k)] = {p.u - u0, p.v - v0};
      f.depth[size_t(k)] = p.depth;
    }
    f.area2 = cross(f.corner[0], f.corner[1], f.corner[2]);
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
  std::vector<Candidate> candidates, chosen;
  std::vector<Polygon> remainder, next;
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      const size_t i = size_t(v) * size + u;
      const float first = first_hits.texels[i].lower;
      bounds[i] = first;
      if (first >= 1.0f) continue;
      const Polygon square{{double(u), double(v)}, {u + 1.0, double(v)}, {u + 1.0, v + 1.0}, {double(u), v + 1.0}};
      candidates.clear();
      // The depth gap: the deepest of the triangles that come within `gap` of the first hit.
      double gap_depth = -std::numeric_limits<double>::infinity();
      for (uint32_t f : binned[size_t(v / kBin) * bins + u / kBin]) {
        const OverSquare over = over_square(footprints[f], square);
        if (over.shallowest <= double(first) + gap) gap_depth = std::max(gap_depth, over.deepest);
        if (over.area > 0) candidates.push_back({over.deepest, over.area, f});
      }
      std::sort(candidates.begin(), candidates.end(),
                [](const Candidate& a, const Candidate& b) { return a.deepest < b.deepest; });
      // The smallest depth B such that the triangles no deeper than B over the square cover it: the
      // shortest covering prefix of the candidates by depth. Subtracted one by one in depth order,
      // the square's remainder tells at each step; on a dense square (many small triangles cutting it
      // up before a large one comes) that fragments, and the prefix is then found by bisection
      // (covering only grows with the prefix), each prefix subtracted largest part first.
      double cover_depth = std::numeric_limits<double>::infinity();
      remainder.assign(1, square);
      size_t not_covering = 0;  // a prefix length known not to cover
      bool fragmented = false;
      for (size_t c = 0; c < candidates.size(); ++c) {
        subtract_from(remainder, footprints[candidates[c].footprint], next);
        if (remainder.empty()) {
          cover_depth = candidates[c].deepest;
          break;
        }
        not_covering = c + 1;
        if (remainder.size() > kIncrementalPieces) {
          fragmented = true;
          break;
        }
      }
      auto prefix_covers = [&](size_t count) {
        chosen.assign(candidates.begin(), candidates.begin() + ptrdiff_t(count));
        return covers(chosen, footprints, square, remainder, next);
      };
      if (fragmented && prefix_covers(candidates.size())) {
        size_t lo = not_covering, hi = candidates.size();  // the shortest covering prefix is in (lo, hi]
        while (hi - lo > 1) {
          const size_t mid = lo + (hi - lo) / 2;
          (prefix_covers(mid) ? hi : lo) = mid;
        }
        cover_depth = candidates[hi - 1].deepest;
      }
      const double depth = std::min(cover_depth, gap_depth > -std::numeric_limits<double>::infinity()
                                                     ? gap_depth
                                                     : std::numeric_limits<double>::infinity());
      if (depth == std::numeric_limits<double>::infinity()) continue;
      const double entry = depth + tolerance - slack;
      if (entry >= double(first)) continue;
      bounds[i] = std::max(0.0f, float_at_least(entry));
    }
  return bounds;
}

}  // namespace shadowtiles
