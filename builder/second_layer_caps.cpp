#include "builder/second_layer_caps.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <utility>

#include "builder/overlapping_box_pairs.hpp"
#include "builder/second_layer_rule.hpp"

namespace shadowtiles {
namespace {

constexpr double kWiden = 1.0 / (1 << 20);  // texels the occluder's edges are widened by
constexpr double kEpsilonShrink = 1.0 - 1.0 / (1 << 20);
constexpr uint32_t kCell = 8;               // texels per grid cell side
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Texels a footprint's box is padded by where it bounds a clip: far above the clips' rounding (ulps of
// coordinates up to 2^20 texels) and far below a texel.
constexpr double kBoxPad = 1.0 / 256;
// Texels of a pair's box up to which its regions are tested texel by texel before any clip: near
// cover's slivers rarely matter, so it pays on larger boxes than the regions behind by epsilon do
// (honolulu 16384^2: either limit prunes nearly as much as no limit; fzk_haus' walls span thousands).
constexpr uint64_t kNearTestTexels = 256, kBehindTestTexels = 32;

struct Prepared {
  std::array<LightSpacePoint, 3> p;
  double lo_u, hi_u, lo_v, hi_v, zmin, zmax;
  bool edge_on;
  double gu = 0, gv = 0;             // depth per texel along u, v
  // A bound on the error of gu and gv, depth per texel: near edge-on slivers the normal's z cancels,
  // so depth_at may stray from the plane through the vertices by this times the distance to p[0].
  double gradient_error = 0;
  std::array<double, 3> A{}, B{}, widen{};  // inward edge k: A (u - p_k.u) + B (v - p_k.v) + widen >= 0
  // Box of the footprint with its edges widened (the corners of the widened triangle), which holds
  // every point covered_by keeps; infinite for slivers whose widened corners are ill-conditioned.
  double reach_lo_u = -kInfinity, reach_hi_u = kInfinity, reach_lo_v = -kInfinity, reach_hi_v = kInfinity;
  double reach = kInfinity;  // how far a widened corner may lie from its vertex, at the most
  // A sharp corner's widened edges meet far from it (2^-20 / sin(angle / 2) texels: a sliver on
  // honolulu_airport reached 20 texels past its apex and capped texels there). The exact region lies
  // in the footprint's box, so covered_by also clips to the box padded by kBoxPad when a widened
  // corner lies outside it, and the reach box is clamped to it.
  bool clip_to_box = false;

  double depth_at(double u, double v) const { return p[0].depth + gu * (u - p[0].u) + gv * (v - p[0].v); }
};

// The widened triangle's corner at p_k: where the widened edges k - 1 and k meet.
void widened_reach(Prepared& t) {
  double lo_u = kInfinity, hi_u = -kInfinity, lo_v = kInfinity, hi_v = -kInfinity, reach = 0;
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 2) % 3;  // edge j runs from p_j to p_k
    // A_k (u - p_k.u) + B_k (v - p_k.v) = -widen_k and A_j (u - p_k.u) + B_j (v - p_k.v) = -widen_j
    // (p_k lies on edge j, so both are written about p_k).
    const double det = t.A[k] * t.B[j] - t.A[j] * t.B[k];
    // hypot(A, B) of both edges, as prepare() left it in widen (a power-of-two scale: exact).
    const double scale = (t.widen[k] / kWiden) * (t.widen[j] / kWiden);
    if (!(std::fabs(det) > 1e-6 * scale)) return;  // a corner sharper than 1e-6 rad: keep the box infinite
    const double du = (-t.widen[k] * t.B[j] + t.widen[j] * t.B[k]) / det;
    const double dv = (-t.A[k] * t.widen[j] + t.A[j] * t.widen[k]) / det;
    // Rounding of the solve (|du|, |dv| <= 2^-20 / 1e-6 texels) is covered by a further 2^-20 texels.
    const double u = t.p[k].u + du, v = t.p[k].v + dv, pad = kWiden + std::fabs(du) + std::fabs(dv);
    lo_u = std::min(lo_u, u - pad), hi_u = std::max(hi_u, u + pad);
    lo_v = std::min(lo_v, v - pad), hi_v = std::max(hi_v, v + pad);
    reach = std::max(reach, pad);
  }
  t.reach_lo_u = lo_u, t.reach_hi_u = hi_u, t.reach_lo_v = lo_v, t.reach_hi_v = hi_v;
  t.reach = reach;
}

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
  const double nz_terms = std::fabs(bu * cv) + std::fabs(bv * cu);
  t.gradient_error = 4e-16 / std::fabs(nz) *
                     (std::fabs(bv * cd) + std::fabs(bd * cv) + std::fabs(bd * cu) + std::fabs(bu * cd) +
                      (std::fabs(t.gu) + std::fabs(t.gv)) * nz_terms);
  const double s = nz > 0 ? 1.0 : -1.0;
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& p = t.p[k];
    const LightSpacePoint& q = t.p[(k + 1) % 3];
    t.A[k] = -s * (q.v - p.v);
    t.B[k] = s * (q.u - p.u);
    t.widen[k] = kWiden * std::hypot(t.A[k], t.B[k]);
  }
  widened_reach(t);
  const double lo_u = t.lo_u - kBoxPad, hi_u = t.hi_u + kBoxPad, lo_v = t.lo_v - kBoxPad, hi_v = t.hi_v + kBoxPad;
  t.clip_to_box = !(t.reach_lo_u >= lo_u && t.reach_hi_u <= hi_u && t.reach_lo_v >= lo_v && t.reach_hi_v <= hi_v);
  if (t.clip_to_box) {
    t.reach_lo_u = std::max(t.reach_lo_u, lo_u), t.reach_hi_u = std::min(t.reach_hi_u, hi_u);
    t.reach_lo_v = std::max(t.reach_lo_v, lo_v), t.reach_hi_v = std::min(t.reach_hi_v, hi_v);
  }
  return t;
}

struct Polygon {
  Polygon() {}  // `at` left uninitialised: only its first `count` points are ever read
  union {
    std::array<LightSpacePoint, 24> at;
  };
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

// True when an edge of `back` separates it from `front`'s widened footprint, so that covered_by
// keeps nothing: `front`'s vertices outside the edge by more than its corners' reach.
bool apart_across_back(const Prepared& back, const Prepared& front) {
  if (!std::isfinite(front.reach)) return false;
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& e = back.p[k];
    const double beyond = -front.reach * back.widen[k] / kWiden;  // reach in units of back's edge function
    auto outside = [&](const LightSpacePoint& x) { return back.A[k] * (x.u - e.u) + back.B[k] * (x.v - e.v) < beyond; };
    if (outside(front.p[0]) && outside(front.p[1]) && outside(front.p[2])) return true;
  }
  return false;
}

// Could `back` lie behind `front` by more than `gap` anywhere covered_by keeps? For each widened
// edge of `front`, the part of `back` inside it holds every kept point, and the depth gap back -
// front, linear on `back`, is largest at that part's vertices: back's vertices inside, and where
// back's edges cross the line. False when one edge's part stays at or under `gap` (less a slack for
// the rounding of the gaps), or is empty (`back` wholly outside that widened edge: apart). It is what
// makes mesh neighbours cheap: a triangle beside `front`, across a shared edge or vertex, keeps only
// a sliver 2^-20 texels wide along `front`'s edge, where the gap is near 0 (both planes hold the
// shared vertices), whereas the pair's boxes overlap widely. Rounding that misplaces a vertex near a
// widened edge moves it by far less than the widening, so the exact region stays inside the bound.
// Division-free: a crossing's gap exceeds `gap` when the weighted sum below is positive.
bool behind_near_front_edges(const Prepared& back, const Prepared& front, double gap) {
  std::array<double, 3> excess;  // each vertex's gap less the threshold
  // The slack's scale: the gaps' magnitudes, and the front plane's slope times the absolute
  // coordinates, since the clips' crossing points are rounded to ulps of u and v (up to 65536
  // texels): on a steep front that rounding alone can put a clipped point behind by the threshold,
  // and such a pair must go on to the clips as before (a review found caps above the reference's
  // without this term: steep fronts, |gradient| >= 1e3 per texel, gaps just under the threshold).
  double scale = 1 + 1e-6 * (std::fabs(front.gu * front.p[0].u) + std::fabs(front.gv * front.p[0].v));
  for (int i = 0; i < 3; ++i) {
    const double du = back.p[i].u - front.p[0].u, dv = back.p[i].v - front.p[0].v;
    excess[i] = back.p[i].depth - front.depth_at(back.p[i].u, back.p[i].v);
    scale = std::max(scale, std::fabs(back.p[i].depth) + std::fabs(front.p[0].depth) + std::fabs(front.gu * du) +
                                std::fabs(front.gv * dv));
  }
  const double threshold = gap - 1e-9 * scale;
  for (double& x : excess) x -= threshold;
  // Nowhere behind `front`'s plane by more than the threshold: every part's vertices and crossings
  // below are blends of these (the test below would find no edge exceeding it). Most mesh
  // neighbours end here, before the edge functions (30 % of honolulu's calls, half of oahu's).
  if (!(excess[0] > 0) && !(excess[1] > 0) && !(excess[2] > 0)) return false;
  // One edge at a time, stopping at the first whose part keeps nothing behind by the threshold: an
  // edge with `back` wholly outside it (apart) has no vertex inside and no crossing, so it is one too.
  for (int k = 0; k < 3; ++k) {
    const LightSpacePoint& e = front.p[k];
    std::array<double, 3> f;  // back's vertex i against front's widened edge k
    for (int i = 0; i < 3; ++i)
      f[i] = front.A[k] * (back.p[i].u - e.u) + front.B[k] * (back.p[i].v - e.v) + front.widen[k];
    bool exceeds = false;
    for (int i = 0; i < 3 && !exceeds; ++i) {
      const int j = i == 2 ? 0 : i + 1;
      const double fi = f[i], fj = f[j];
      if (fi >= 0) exceeds = excess[i] > 0;
      // The crossing, (fi e_j - fj e_i) / (fi - fj) with one of fi, fj negative: the sign of the sum.
      if (!exceeds && (fi >= 0) != (fj >= 0)) exceeds = fi >= 0 ? excess[i] * -fj + excess[j] * fi > 0
                                                                : excess[j] * fi - excess[i] * fj < 0;
    }
    if (!exceeds) return false;
  }
  return true;
}

// The part of `back` inside `front`'s footprint (its edges widened as the header says), into
// `covered` (`scratch`: working space); false when empty. The caller has ruled out a separating edge.
bool covered_by(const Prepared& back, const Prepared& front, Polygon& covered, Polygon& scratch) {
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
  if (front.clip_to_box) {
    const double lo_u = front.lo_u - kBoxPad, hi_u = front.hi_u + kBoxPad;
    const double lo_v = front.lo_v - kBoxPad, hi_v = front.hi_v + kBoxPad;
    auto keep = [&](auto inside) {
      clip(*current, *next, inside);
      std::swap(current, next);
      return current->count >= 3;
    };
    if (!keep([&](const LightSpacePoint& x) { return x.u - lo_u; }) ||
        !keep([&](const LightSpacePoint& x) { return hi_u - x.u; }) ||
        !keep([&](const LightSpacePoint& x) { return x.v - lo_v; }) ||
        !keep([&](const LightSpacePoint& x) { return hi_v - x.v; }))
      return false;
  }
  if (current != &covered) {
    std::copy_n(current->at.begin(), current->count, covered.at.begin());
    covered.count = current->count;
  }
  return true;
}

// The part of `covered` (on `back`, inside `front`'s footprint) lying behind `front` by at least
// `gap` and, when `most` is finite, by at most `most`, into `region`; false when empty.
bool region_behind(const Polygon& covered, const Prepared& front, double gap, double most, Polygon& region,
                   Polygon& scratch) {
  if (!std::isfinite(most)) {
    clip(covered, region, [&](const LightSpacePoint& x) { return x.depth - front.depth_at(x.u, x.v) - gap; });
    return region.count >= 3;
  }
  clip(covered, scratch, [&](const LightSpacePoint& x) { return x.depth - front.depth_at(x.u, x.v) - gap; });
  if (scratch.count < 3) return false;
  clip(scratch, region, [&](const LightSpacePoint& x) { return most - (x.depth - front.depth_at(x.u, x.v)); });
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

}  // namespace

struct SecondLayerScratch::Buffers {
  std::vector<Prepared> prepared;
  std::vector<uint32_t> candidates;
  OverlappingBoxPairsScratch pair_grid;
  std::vector<std::vector<float>> pyramid, lower_pyramid;
  std::vector<uint32_t> sides;
};

SecondLayerScratch::SecondLayerScratch() = default;
SecondLayerScratch::Buffers& SecondLayerScratch::buffers() {
  if (!buffers_) buffers_ = std::make_unique<Buffers>();  // first use, or moved from
  return *buffers_;
}
SecondLayerScratch::~SecondLayerScratch() = default;
SecondLayerScratch::SecondLayerScratch(SecondLayerScratch&&) noexcept = default;
SecondLayerScratch& SecondLayerScratch::operator=(SecondLayerScratch&&) noexcept = default;


std::vector<float> second_layer_caps(const LightSpaceScene& scene, TileCoord tile, double coplanar_epsilon,
                                     const TileIntervals& intervals, float exit_margin, SecondLayerCapCounts* counts,
                                     std::vector<float> storage, SecondLayerScratch* reuse, bool texel_tests) {
  std::optional<SecondLayerScratch> own_scratch;
  SecondLayerScratch::Buffers& buffers = (reuse ? *reuse : own_scratch.emplace()).buffers();
  const uint32_t size = scene.layout().tile_size();
  const TexelWindow window{double(tile.x) * size, double(tile.y) * size, size};
  std::vector<float> cap = std::move(storage);
  cap.assign(size_t(size) * size, std::numeric_limits<float>::infinity());
  const Scene& world = scene.scene();
  const auto triangles = scene.triangles_of(tile);
  SecondLayerCapCounts local;

  std::vector<Prepared>& prepared = buffers.prepared;
  prepared.clear();
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
  std::vector<uint32_t>& candidates = buffers.candidates;
  candidates.clear();
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
  std::vector<std::vector<float>>& pyramid = buffers.pyramid;
  std::vector<std::vector<float>>& lower_pyramid = buffers.lower_pyramid;
  std::vector<uint32_t>& sides = buffers.sides;
  sides.assign(1, cells);
  if (pyramid.empty()) pyramid.resize(1), lower_pyramid.resize(1);
  {  // (references into the pyramids: the levels below may reallocate them)
    std::vector<float>& cell_upper = pyramid[0];
    std::vector<float>& cell_lower = lower_pyramid[0];
    cell_upper.assign(size_t(cells) * cells, kNothing), cell_lower.assign(size_t(cells) * cells, kNone);
    for (uint32_t v = 0; v < size; ++v)
      for (uint32_t u = 0; u < size; ++u) {
        const DepthInterval& t = intervals.at(u, v);
        if (t.upper > t.lower && t.lower < 1.0f) {
          const size_t cell = size_t(v / kCell) * cells + u / kCell;
          cell_upper[cell] = std::max(cell_upper[cell], t.upper);
          cell_lower[cell] = std::min(cell_lower[cell], t.lower);
        }
      }
  }
  while (sides.back() > 1) {
    const uint32_t from = sides.back(), to = (from + 1) / 2;
    const size_t at_level = sides.size();
    if (pyramid.size() <= at_level) pyramid.resize(at_level + 1), lower_pyramid.resize(at_level + 1);
    std::vector<float>& level = pyramid[at_level];
    std::vector<float>& lower_level = lower_pyramid[at_level];
    level.assign(size_t(to) * to, kNothing), lower_level.assign(size_t(to) * to, kNone);
    const std::vector<float>& fine = pyramid[at_level - 1];
    const std::vector<float>& fine_lower = lower_pyramid[at_level - 1];
    for (uint32_t y = 0; y < from; ++y)
      for (uint32_t x = 0; x < from; ++x) {
        const size_t at = size_t(y / 2) * to + x / 2;
        level[at] = std::max(level[at], fine[size_t(y) * from + x]);
        lower_level[at] = std::min(lower_level[at], fine_lower[size_t(y) * from + x]);
      }
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
  Polygon covered, region, scratch;
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

  // Could a region of `back` behind `front` by [gap_least, gap_most], inside [lo, hi] (global texels),
  // change an interval? Per texel with an exit, the region's depths in the square are bounded by both
  // planes over the whole square (on `back`, and between front + gap_least and front + gap_most):
  // near cover (`with_floor`) needs a point at or below the texel's floor (lower_caps_above_floor), and the
  // bound the region gives there, max(floor, its shallowest), must lie below the cap so far and
  // below upper + margin as apply_exit_caps computes it; elsewhere the caps may stay higher, as
  // the pruned regions above (the intervals are the same). Most near regions are slivers that
  // lower nothing (0.4 % lower a cap on honolulu 16384^2), so most such pairs end here before their
  // clips. The slack covers the clips' rounding.
  auto region_could_matter = [&](const Prepared& back, const Prepared& front, double lo_u, double hi_u, double lo_v,
                                 double hi_v, double gap_least, double gap_most, bool with_floor, uint64_t limit) {
    const double size = window.size;
    lo_u -= window.u0 + kWiden, hi_u += kWiden - window.u0, lo_v -= window.v0 + kWiden, hi_v += kWiden - window.v0;
    if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) return false;
    auto texel = [&](double at) { return uint32_t(std::clamp(std::floor(at), 0.0, size - 1)); };
    const uint32_t i0 = texel(lo_u), i1 = texel(hi_u), j0 = texel(lo_v), j1 = texel(hi_v);
    // A large box costs more texels than the clips would (a wall over a floor on fzk_haus spans
    // thousands, and its sliver region visits only the texels its rows reach): leave it to them.
    if (!texel_tests || uint64_t(i1 - i0 + 1) * (j1 - j0 + 1) > limit) return true;
    const double half = 0.5 * (std::fabs(back.gu) + std::fabs(back.gv));
    const double front_half = 0.5 * (std::fabs(front.gu) + std::fabs(front.gv));
    // Texel centres lie within this many texels of either triangle's p[0] (the distance depth_at scales by).
    auto reach_from = [&](const Prepared& t) {
      return std::fabs(window.u0 - t.p[0].u) + std::fabs(window.v0 - t.p[0].v) + 2 * size;
    };
    const double slack = 1e-9 * (1 + std::fabs(back.zmin) + std::fabs(back.zmax) + std::fabs(front.zmin) +
                                 std::fabs(front.zmax) +
                                 (std::fabs(back.gu) + std::fabs(back.gv)) *
                                     (std::fabs(window.u0) + std::fabs(window.v0) + 2 * size + reach_from(back)) +
                                 (std::fabs(front.gu) + std::fabs(front.gv)) *
                                     (std::fabs(window.u0) + std::fabs(window.v0) + 2 * size + reach_from(front))) +
                         back.gradient_error * reach_from(back) + front.gradient_error * reach_from(front);
    for (uint32_t j = j0; j <= j1; ++j)
      for (uint32_t i = i0; i <= i1; ++i) {
        const DepthInterval& interval = intervals.at(i, j);
        if (!(interval.upper > interval.lower && interval.lower < 1.0f)) continue;
        const double floor_depth = with_floor ? double(interval.lower) + floor_offset : -kInfinity;
        const double cu = window.u0 + i + 0.5, cv = window.v0 + j + 0.5;
        const double centre = back.depth_at(cu, cv), front_centre = front.depth_at(cu, cv);
        const double deepest = std::min({centre + half, back.zmax, front_centre + front_half + gap_most}) + slack;
        if (deepest < floor_depth) continue;
        const double shallowest =
            std::max({centre - half, back.zmin, front_centre - front_half + gap_least}) - slack;
        const double bound = std::max(floor_depth, shallowest);
        if (!(bound < cap[size_t(j) * window.size + i]) || float(bound) - exit_margin >= interval.upper) continue;
        return true;
      }
    return false;
  };

  auto lower_by_region = [&](const Prepared& back, const Prepared& front) {
    if (!(back.zmax > front.zmin + same_surface)) return;  // nowhere behind it
    // Behind by too little wherever `back` meets a widened edge of `front`, or outside one: the
    // cheapest test that rejects most pairs whose boxes overlap (oahu 16384^2: 5.5 million of the 7.6
    // million ordered pairs that pass the test above are mesh neighbours, which it rejects).
    if (!behind_near_front_edges(back, front, same_surface)) return;
    // Every point the clips keep lies in this box (on `back`, inside `front`'s widened footprint),
    // and on `back`'s plane, so the depth gap back - front there is within the gap's range over the
    // box's corners (a linear function), give or take the slack for rounding.
    const double lo_u = std::max(back.lo_u, front.reach_lo_u), hi_u = std::min(back.hi_u, front.reach_hi_u);
    const double lo_v = std::max(back.lo_v, front.reach_lo_v), hi_v = std::min(back.hi_v, front.reach_hi_v);
    if (lo_u > hi_u || lo_v > hi_v) return;  // footprints apart
    // Footprints apart across an edge of `back` (across one of `front`'s, the test above saw it).
    if (apart_across_back(back, front)) return;
    const double du = hi_u - lo_u, dv = hi_v - lo_v;
    const double gap_gu = back.gu - front.gu, gap_gv = back.gv - front.gv;
    const double back_at_lo = back.depth_at(lo_u, lo_v), front_at_lo = front.depth_at(lo_u, lo_v);
    const double gap_at_lo = back_at_lo - front_at_lo;
    const double gap_most = gap_at_lo + std::max(gap_gu * du, 0.0) + std::max(gap_gv * dv, 0.0);
    const double gap_least = gap_at_lo + std::min(gap_gu * du, 0.0) + std::min(gap_gv * dv, 0.0);
    const double back_least = back_at_lo + std::min(back.gu * du, 0.0) + std::min(back.gv * dv, 0.0);
    const double front_least = front_at_lo + std::min(front.gu * du, 0.0) + std::min(front.gv * dv, 0.0);
    const double slack = 1e-9 * (1 +
                                 (std::fabs(back.gu) + std::fabs(front.gu)) *
                                     (du + std::fabs(lo_u - back.p[0].u) + std::fabs(lo_u - front.p[0].u)) +
                                 (std::fabs(back.gv) + std::fabs(front.gv)) *
                                     (dv + std::fabs(lo_v - back.p[0].v) + std::fabs(lo_v - front.p[0].v))) +
                         back.gradient_error *
                             (du + dv + std::fabs(lo_u - back.p[0].u) + std::fabs(lo_v - back.p[0].v)) +
                         front.gradient_error *
                             (du + dv + std::fabs(lo_u - front.p[0].u) + std::fabs(lo_v - front.p[0].v));
    if (!(gap_most + slack > same_surface)) {  // `back` is nowhere behind `front` where they overlap
      ++local.skipped;
      return;
    }
    // Every point of either region is at least this deep: behind `front`, and on `back`.
    const double bound = std::max({back.zmin, front.zmin + same_surface, back_least - slack,
                                   std::min(front_least + same_surface, back.zmax) - slack});
    // The pair's footprint boxes' overlap, a texel wider each way, for the pyramids.
    const double box_lo_u = std::max(back.lo_u, front.lo_u) - 1, box_hi_u = std::min(back.hi_u, front.hi_u) + 1;
    const double box_lo_v = std::max(back.lo_v, front.lo_v) - 1, box_hi_v = std::min(back.hi_v, front.hi_v) + 1;
    if (!matters(bound, box_lo_u, box_hi_u, box_lo_v, box_hi_v)) {
      ++local.skipped;
      return;
    }
    // Near cover needs a point of `back` at or below some texel's floor in the pair's box. A small box
    // is also tested texel by texel (region_could_matter) before the clips.
    constexpr bool kWithFloor = true;
    const bool behind_by_epsilon = back.zmax > front.zmin + epsilon && gap_most + slack > epsilon &&
                                   region_could_matter(back, front, lo_u, hi_u, lo_v, hi_v, epsilon, kInfinity,
                                                       !kWithFloor, kBehindTestTexels);
    const bool near = back.zmin <= front.zmax + epsilon && gap_least - slack <= epsilon &&
                      back.zmax >= double(smallest_lower(box_lo_u, box_hi_u, box_lo_v, box_hi_v)) + floor_offset &&
                      region_could_matter(back, front, lo_u, hi_u, lo_v, hi_v, same_surface, epsilon, kWithFloor,
                                          kNearTestTexels);
    if (!behind_by_epsilon && !near) {
      ++local.skipped;
      return;
    }
    ++local.pairs_tested;
    double shallowest = 0;
    if (!covered_by(back, front, covered, scratch)) return;
    // Behind by epsilon: the second layer wherever it lies.
    if (behind_by_epsilon && region_behind(covered, front, epsilon, kInfinity, region, scratch) &&
        region_matters(shallowest)) {
      ++local.regions;
      for (unsigned k = 1; k + 1 < region.count; ++k)
        lower_caps_by_triangle(region.at[0], region.at[k], region.at[k + 1], window, cap, &local.texels);
    }
    // Near cover: behind by less than epsilon, the second layer below each texel's lower + offset.
    if (near && region_behind(covered, front, same_surface, epsilon, region, scratch) &&
        region_matters(shallowest)) {
      ++local.near_regions;
      lower_caps_above_floor(region, window, intervals, floor_offset, exit_margin, cap);
    }
  };
  if (pyramid[sides.size() - 1][0] == kNothing) candidates.clear();  // no exit in the tile: nothing to cap
  for_each_overlapping_pair(buffers.pair_grid, prepared, candidates, window, [&](uint32_t i, uint32_t j) {
    lower_by_region(prepared[i], prepared[j]);
    lower_by_region(prepared[j], prepared[i]);
  });
  if (counts) counts->add(local);
  return cap;
}

}  // namespace shadowtiles
