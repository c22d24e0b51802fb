#include "builder/receiver_surface_caps.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "common/float_rounding.hpp"

namespace shadowtiles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Why the fast paths give the clipping's float, bit for bit:
// - Skipped texels: every vertex the clipping computes lies within a rounding error (~1e-12 texels at
//   2^16-texel maps) of the triangle and of the half-planes already applied, so a square farther than
//   kMargin texels from the triangle clips to nothing. Row spans are widened by kMargin accordingly.
// - Interior texels (square inside the triangle by kMargin): the clipped polygon is the square's four
//   corners, each computed on the triangle's plane up to a few ulps; its minimum is within eps of the
//   plane's exact value at the shallowest corner, and so is the closed form. Where x - eps and x + eps
//   round to the same float, every value between them does (rounding is monotone), the clipping's
//   included; elsewhere the texel is clipped. eps is ~200x the error analysis' bound (kEpsScale).
// - Edge texels take the same closed form where the exact minimum is a point the clipping computes
//   within the same rounding: the shallowest corner when it lies inside the triangle by kMargin, or,
//   where one edge only reaches the square and that corner lies outside it by kMargin, the shallower
//   end of the edge's chord through the square (chord_shallowest). The tests compare every path with
//   the clipping bit for bit.
constexpr double kMargin = 1.0 / (1 << 20);      // texels
constexpr double kEpsScale = 1.0 / (1ull << 40);  // relative to the magnitudes the errors scale with

struct ClipVertex {
  double u, v, depth;
};

// A triangle clipped by 4 half-planes has at most 7 vertices in exact arithmetic; rounding can make an
// intermediate polygon slightly non-convex, and a clip emits at most (kept + sign changes) vertices:
// 3 -> 4 -> 6 -> 9 -> 13 at worst.
struct ClipPolygon {
  std::array<ClipVertex, 13> at;
  unsigned count = 0;
};

// Sutherland-Hodgman against one axis-aligned edge: keeps the side where sign * (coord - bound) >= 0.
// Operation for operation the original per-texel clipping, so its results are reproduced exactly.
void clip_polygon(const ClipPolygon& in, ClipPolygon& out, bool along_u, double bound, double sign) {
  out.count = 0;
  const unsigned n = in.count;
  for (unsigned k = 0; k < n; ++k) {
    const ClipVertex& p = in.at[k];
    const ClipVertex& q = in.at[k + 1 == n ? 0 : k + 1];
    const double dp = sign * ((along_u ? p.u : p.v) - bound), dq = sign * ((along_u ? q.u : q.v) - bound);
    if (dp >= 0) out.at[out.count++] = p;
    if ((dp >= 0) != (dq >= 0)) {
      const double t = dp / (dp - dq);
      out.at[out.count++] = {p.u + t * (q.u - p.u), p.v + t * (q.v - p.v), p.depth + t * (q.depth - p.depth)};
    }
  }
}

// The triangle's bounding box (global texels): clips it does not reach by kMargin are skipped.
struct Box {
  double lo_u, hi_u, lo_v, hi_v;
};

// Exact: the shallowest depth of the triangle clipped to [su, su+1] x [sv, sv+1]; +inf if nothing is left.
// A clip whose line the triangle's box stays kMargin clear of keeps every vertex (all within rounding
// of the triangle) and adds none, so skipping it leaves the polygon, and the result, unchanged.
double clipped_shallowest(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c, const Box& box,
                          double su, double sv) {
  ClipPolygon first, second;
  ClipPolygon* polygon = &first;
  ClipPolygon* scratch = &second;
  first.at[0] = {a.u, a.v, a.depth};
  first.at[1] = {b.u, b.v, b.depth};
  first.at[2] = {c.u, c.v, c.depth};
  first.count = 3;
  auto clip = [&](bool along_u, double bound, double sign) {
    clip_polygon(*polygon, *scratch, along_u, bound, sign);
    std::swap(polygon, scratch);
    return polygon->count != 0;
  };
  if (box.lo_u < su + kMargin && !clip(true, su, 1)) return kInf;
  if (box.hi_u > su + 1 - kMargin && !clip(true, su + 1, -1)) return kInf;
  if (box.lo_v < sv + kMargin && !clip(false, sv, 1)) return kInf;
  if (box.hi_v > sv + 1 - kMargin && !clip(false, sv + 1, -1)) return kInf;
  double shallowest = polygon->at[0].depth;
  for (unsigned k = 0; k < polygon->count; ++k) shallowest = std::min(shallowest, polygon->at[k].depth);
  return shallowest;
}

// The triangle's u-extent within the band vlo <= v <= vhi: its vertices in the band and its edges'
// crossings of the band's borders (lo > hi when it misses the band).
void u_extent_in_band(const std::array<const LightSpacePoint*, 3>& tri, double vlo, double vhi, double& lo,
                      double& hi) {
  lo = kInf;
  hi = -kInf;
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& p = *tri[k];
    const LightSpacePoint& q = *tri[(k + 1) % 3];
    if (p.v >= vlo && p.v <= vhi) {
      lo = std::min(lo, p.u);
      hi = std::max(hi, p.u);
    }
    for (double y : {vlo, vhi})
      if ((p.v < y) != (q.v < y)) {
        const double u = p.u + (y - p.v) / (q.v - p.v) * (q.u - p.u);
        lo = std::min(lo, u);
        hi = std::max(hi, u);
      }
  }
}

// Inside test with margin for one edge: A * (u - pu) + B * (v - pv) >= threshold on the inner side.
struct EdgeTest {
  double pu, pv, A, B, threshold;
};

// What the interior texels need: the edges (oriented inward), the plane's slopes and the error bound.
struct InteriorPlane {
  std::array<EdgeTest, 3> edges;
  double gu = 0, gv = 0;  // depth change per texel along u, v
  double eps = 0;         // bound on |closed form - clipping| (see the note at the top)
};

// False when the triangle cannot hold a whole texel square (area < 2 texels², edge-on) or its plane
// is too ill-conditioned to bound.
bool make_interior_plane(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                         InteriorPlane& plane) {
  const double bu = b.u - a.u, bv = b.v - a.v, bd = b.depth - a.depth;
  const double cu = c.u - a.u, cv = c.v - a.v, cd = c.depth - a.depth;
  const double nx = bv * cd - bd * cv, ny = bd * cu - bu * cd, nz = bu * cv - bv * cu;
  if (!(std::fabs(nz) >= 4.0)) return false;  // |nz| is twice the area; a square needs area >= 2
  const double s = nz > 0 ? 1.0 : -1.0;
  const std::array<const LightSpacePoint*, 3> tri{&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& p = *tri[k];
    const LightSpacePoint& q = *tri[(k + 1) % 3];
    EdgeTest& e = plane.edges[k];
    e = {p.u, p.v, -s * (q.v - p.v), s * (q.u - p.u), 0};
    e.threshold = kMargin * (std::fabs(e.A) + std::fabs(e.B));
  }
  plane.gu = -nx / nz;
  plane.gv = -ny / nz;
  // Error terms: the clipping's (rounding of coordinates and depths, scaled by the slopes) and the
  // closed form's (cancellation in the cross products, amplified by (|p1| + |p2|) / |p1 - p2|).
  const double depth_scale = std::max({std::fabs(a.depth), std::fabs(b.depth), std::fabs(c.depth)});
  const double u_scale = std::max({std::fabs(a.u), std::fabs(b.u), std::fabs(c.u)});
  const double v_scale = std::max({std::fabs(a.v), std::fabs(b.v), std::fabs(c.v)});
  const double u_extent = std::max(std::fabs(bu), std::fabs(cu)), v_extent = std::max(std::fabs(bv), std::fabs(cv));
  const double kz = (std::fabs(bu * cv) + std::fabs(bv * cu)) / std::fabs(nz);
  const double kx = (std::fabs(bv * cd) + std::fabs(bd * cv)) / std::fabs(nz);
  const double ky = (std::fabs(bd * cu) + std::fabs(bu * cd)) / std::fabs(nz);
  const double agu = std::fabs(plane.gu), agv = std::fabs(plane.gv);
  plane.eps = kEpsScale * (depth_scale + agu * u_scale + agv * v_scale + (kx + agu * kz) * u_extent +
                           (ky + agv * kz) * v_extent);
  return std::isfinite(plane.eps);
}

// The float that every value within eps of x rounds to, when they all round alike (rounding is
// monotone, so x - eps and x + eps decide); false when x is too close to a rounding boundary to call.
bool sure_float(double x, double eps, float& value) {
  const float below = float(x - eps), above = float(x + eps);
  value = below;
  return below == above;
}

// True when the point lies inside the triangle by kMargin (every edge's margin test holds).
bool inside_by_margin(const InteriorPlane& plane, double u, double v) {
  for (const EdgeTest& e : plane.edges)
    if (!(e.A * (u - e.pu) + e.B * (v - e.pv) >= e.threshold)) return false;
  return true;
}

// When exactly one edge of the triangle reaches the square (the other two clear of it by kMargin) and
// the square's shallowest corner (cu, cv) lies outside that edge by kMargin, the triangle's shallowest
// point in the square lies on the edge's chord through the square: the segment from any point of
// their intersection to the corner crosses the chord, and the plane only falls along it. So `x` is the
// plane's value at one end of the chord. False when the texel is not such a case.
bool chord_shallowest(const InteriorPlane& plane, const std::array<const LightSpacePoint*, 3>& tri, double su,
                      double sv, double cu, double cv, double& x) {
  int crossing = -1;
  for (int k = 0; k < 3; ++k) {
    const EdgeTest& e = plane.edges[k];
    const double least = e.A * ((e.A >= 0 ? su : su + 1) - e.pu) + e.B * ((e.B >= 0 ? sv : sv + 1) - e.pv);
    if (least >= e.threshold) continue;  // the square lies inside this edge
    if (crossing >= 0) return false;     // a second edge reaches it
    crossing = k;
  }
  if (crossing < 0) return false;
  const EdgeTest& e = plane.edges[crossing];
  if (!(e.A * (cu - e.pu) + e.B * (cv - e.pv) <= -e.threshold)) return false;
  const LightSpacePoint& p = *tri[crossing];
  const LightSpacePoint& q = *tri[(crossing + 1) % 3];
  double t0 = -kInf, t1 = kInf;  // the edge's line p + t (q - p) inside the square (Liang-Barsky)
  auto slab = [&](double from, double delta, double lo, double hi) {
    if (delta == 0) return from >= lo && from <= hi;
    double ta = (lo - from) / delta, tb = (hi - from) / delta;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    return true;
  };
  if (!slab(p.u, q.u - p.u, su, su + 1) || !slab(p.v, q.v - p.v, sv, sv + 1) || !(t0 <= t1)) return false;
  const double rise = q.depth - p.depth;
  x = p.depth + (rise > 0 ? t0 : t1) * rise;
  return true;
}

// Texels [first, last] of row sv whose squares lie inside the triangle by kMargin (empty: first > last).
void interior_span(const InteriorPlane& plane, double sv, double u0, double& first, double& last) {
  double lo_su = -kInf, hi_su = kInf;  // allowed square origins
  for (const EdgeTest& e : plane.edges) {
    // The square's corner with the smallest edge value sets the condition.
    const double v_corner = e.B >= 0 ? sv : sv + 1;
    const double rest = e.threshold - e.B * (v_corner - e.pv);
    if (e.A > 0) lo_su = std::max(lo_su, e.pu + rest / e.A);           // su >= ...
    else if (e.A < 0) hi_su = std::min(hi_su, e.pu + rest / e.A - 1);  // su + 1 <= ...
    else if (rest > 0) hi_su = -kInf;
  }
  first = std::max(first, std::ceil(lo_su - u0));
  last = std::min(last, std::floor(hi_su - u0));
}

// The texels whose closed squares the triangle's bounding box touches, clamped to the window; false
// when it touches none. Closed: a box starting exactly on a texel border (a heightfield's grid line
// on a tile border) touches the texel left of (below) that border too, so the box is floored less
// one texel, and a box starting on the window's far border still reaches its last column (row).
struct TexelBox {
  uint32_t i0, i1, j0, j1;
};
bool rasterised_box(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                    const TexelWindow& window, TexelBox& box) {
  const uint32_t size = window.size;
  const double lo_u = std::min({a.u, b.u, c.u}) - window.u0, hi_u = std::max({a.u, b.u, c.u}) - window.u0;
  const double lo_v = std::min({a.v, b.v, c.v}) - window.v0, hi_v = std::max({a.v, b.v, c.v}) - window.v0;
  if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) return false;
  box.i0 = uint32_t(std::max(0.0, std::floor(lo_u) - 1)), box.i1 = uint32_t(std::min(size - 1.0, std::floor(hi_u)));
  box.j0 = uint32_t(std::max(0.0, std::floor(lo_v) - 1)), box.j1 = uint32_t(std::min(size - 1.0, std::floor(hi_v)));
  return true;
}

// The texels whose caps apply_exit_caps reads (takes_exit_cap), asked per block of kBlock^2 texels
// and remembered: a triangle whose texel box meets no block holding one can be skipped. Blocks are
// looked at only when a triangle's box reaches them, and a block of a solid answers at its first
// texel, so a tile of misses or of solids costs next to nothing.
class CappedTexelBlocks {
 public:
  static constexpr uint32_t kBlock = 16;

  explicit CappedTexelBlocks(const TileIntervals& intervals)
      : intervals_(intervals), size_(intervals.size), blocks_((intervals.size + kBlock - 1) / kBlock),
        state_(size_t(blocks_) * blocks_, kUnknown) {}

  // Whether the texels lower_caps_by_triangle would visit for (a, b, c) (rasterised_box, which it
  // uses too) hold one that takes a cap: a skip loses nothing.
  bool any_near(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                const TexelWindow& window) {
    TexelBox box;
    if (!rasterised_box(a, b, c, window, box)) return false;  // it would touch nothing
    for (uint32_t bj = box.j0 / kBlock; bj <= box.j1 / kBlock; ++bj)
      for (uint32_t bi = box.i0 / kBlock; bi <= box.i1 / kBlock; ++bi)
        if (block_has_capped(bi, bj)) return true;
    return false;
  }

 private:
  static constexpr uint8_t kUnknown = 2;
  const TileIntervals& intervals_;
  uint32_t size_, blocks_;
  std::vector<uint8_t> state_;  // per block: 0 none, 1 some, kUnknown not looked at yet

  bool block_has_capped(uint32_t bi, uint32_t bj) {
    uint8_t& state = state_[size_t(bj) * blocks_ + bi];
    if (state == kUnknown) {
      state = 0;
      const uint32_t u_end = std::min(size_, (bi + 1) * kBlock), v_end = std::min(size_, (bj + 1) * kBlock);
      for (uint32_t v = bj * kBlock; v < v_end && !state; ++v)
        for (uint32_t u = bi * kBlock; u < u_end; ++u)
          if (takes_exit_cap(intervals_.at(u, v))) {
            state = 1;
            break;
          }
    }
    return state == 1;
  }
};

}  // namespace

void lower_caps_by_triangle(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                            const TexelWindow& window, std::span<float> cap, ReceiverCapCounts* counts) {
  const uint32_t size = window.size;
  const double u0 = window.u0, v0 = window.v0;
  TexelBox texels;
  if (!rasterised_box(a, b, c, window, texels)) return;
  const uint32_t i0 = texels.i0, i1 = texels.i1, j0 = texels.j0, j1 = texels.j1;

  InteriorPlane plane;
  const bool has_interior = make_interior_plane(a, b, c, plane);
  const std::array<const LightSpacePoint*, 3> tri{&a, &b, &c};
  ReceiverCapCounts local;
  const Box box{std::min({a.u, b.u, c.u}), std::max({a.u, b.u, c.u}), std::min({a.v, b.v, c.v}),
                std::max({a.v, b.v, c.v})};
  // No clipped point lies above the triangle's shallowest vertex by more than rounding (far below
  // 1e-12 of a depth in [0, 1]); `floor_cap` is a float at or below every such point, so a texel whose
  // cap is already at or below it keeps its cap whatever the clipping returns: skipped, the result is
  // the same bit for bit (a closed mesh's back faces reach a texel from several regions).
  const double shallowest = std::min({a.depth, b.depth, c.depth});
  const double below = shallowest - 1e-12 * (1.0 + std::fabs(shallowest));
  const float floor_cap = float_at_most(below);
  auto clip_texel = [&](uint32_t i, uint32_t j, double su, double sv) {
    float& slot = cap[size_t(j) * size + i];
    if (slot <= floor_cap) {
      ++local.already_lower;
      return;
    }
    if (has_interior) {
      // The square's shallowest corner on the plane, when it lies inside the triangle by the margin,
      // is the shallowest point of the triangle in the square: the closed form, as for the interior
      // texels (same error bound: the clipped polygon holds that corner, all its vertices within
      // rounding of the plane), where it is not too close to a float rounding boundary to call.
      const double cu = su + (plane.gu > 0 ? 0.0 : 1.0), cv = sv + (plane.gv > 0 ? 0.0 : 1.0);
      float value;
      if (inside_by_margin(plane, cu, cv)) {
        if (sure_float(a.depth + plane.gv * (cv - a.v) + plane.gu * (cu - a.u), plane.eps, value)) {
          slot = std::min(slot, value);
          ++local.corner;
          return;
        }
      } else if (double x; chord_shallowest(plane, tri, su, sv, cu, cv, x) && sure_float(x, plane.eps, value)) {
        slot = std::min(slot, value);
        ++local.chord;
        return;
      }
    }
    slot = std::min(slot, float(clipped_shallowest(a, b, c, box, su, sv)));
  };
  for (uint32_t j = j0; j <= j1; ++j) {
    const double sv = v0 + j;
    double lo, hi;
    u_extent_in_band(tri, sv - kMargin, sv + 1 + kMargin, lo, hi);
    if (!(lo <= hi)) continue;
    const double first = std::max(double(i0), std::floor(lo - u0 - kMargin));
    const double last = std::min(double(i1), std::floor(hi - u0 + kMargin));
    if (first > last) continue;
    double inner_first = first, inner_last = first - 1;
    if (has_interior) {
      inner_last = last;
      interior_span(plane, sv, u0, inner_first, inner_last);
      if (inner_first > inner_last) inner_first = first, inner_last = first - 1;
    }
    const uint32_t span_first = uint32_t(first), span_last = uint32_t(last);
    const uint32_t in_first = uint32_t(inner_first), in_end = uint32_t(inner_last + 1);  // [in_first, in_end)
    for (uint32_t i = span_first; i < in_first; ++i) clip_texel(i, j, u0 + i, sv);
    if (in_first < in_end) {
      // The plane at the square's shallowest corner, rounded to float unless too close to call.
      const double du = plane.gu > 0 ? 0.0 : 1.0, cv = sv + (plane.gv > 0 ? 0.0 : 1.0);
      const double row_depth = a.depth + plane.gv * (cv - a.v);
      float* row = &cap[size_t(j) * size];
      for (uint32_t i = in_first; i < in_end; ++i) {
        if (float value; sure_float(row_depth + plane.gu * ((u0 + i) + du - a.u), plane.eps, value)) {
          row[i] = std::min(row[i], value);
        } else {
          clip_texel(i, j, u0 + i, sv);
          ++local.fallback;
        }
      }
      local.interior += in_end - in_first;
    }
    for (uint32_t i = std::max(in_end, span_first); i <= span_last; ++i) clip_texel(i, j, u0 + i, sv);
    local.clipped += (span_last - span_first + 1) - (in_end - in_first);
  }
  if (counts) {
    counts->add(local);
  }
}

std::vector<float> receiver_surface_caps(const LightSpaceScene& scene, TileCoord tile, ReceiverCapCounts* counts,
                                         std::vector<float> storage, const TileIntervals* intervals) {
  const uint32_t size = scene.layout().tile_size();
  const TexelWindow window{double(tile.x) * size, double(tile.y) * size, size};
  std::vector<float> cap = std::move(storage);
  cap.assign(size_t(size) * size, std::numeric_limits<float>::infinity());
  std::optional<CappedTexelBlocks> capped;
  if (intervals && intervals->size == size) capped.emplace(*intervals);
  auto cap_by = [&](const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
    if (capped && !capped->any_near(a, b, c, window)) {
      if (counts) ++counts->triangles_skipped;
      return;
    }
    lower_caps_by_triangle(a, b, c, window, cap, counts);
  };
  const Scene& world = scene.scene();
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    const LightSpacePoint& a = scene.vertex(tri[0]);
    const LightSpacePoint& b = scene.vertex(tri[1]);
    const LightSpacePoint& c = scene.vertex(tri[2]);
    const MeshKind kind = world.meshes[world.triangle_mesh[t]].kind;
    const double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
    if (kind != MeshKind::open && nz < 0) continue;  // faces the light: an entry surface, the lit side
    cap_by(a, b, c);
  }
  // A patch over a nearly closed mesh's hole bounds its solid like the mesh's own faces: receivers lie
  // below those not facing the light (docs/receiver-contracts.md, "Nearly closed solids").
  for (uint32_t t : scene.patches_of(tile)) {
    const auto& tri = world.patch_triangles[t];
    const LightSpacePoint& a = scene.vertex(tri[0]);
    const LightSpacePoint& b = scene.vertex(tri[1]);
    const LightSpacePoint& c = scene.vertex(tri[2]);
    const double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
    if (nz < 0) continue;
    cap_by(a, b, c);
  }
  return cap;
}

}  // namespace shadowtiles
