#include "builder/entry_cover.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "common/float_rounding.hpp"

namespace shadowtiles {
namespace {

constexpr double kEntrySquareHalf = 0.51;

// The entry rule (DualDepthOptions::entry_slack). `first_prim` is the centre ray's first-hit triangle
// (in the open set when `open`), (cu, cv) the texel centre in tile-local texels, (global_u, global_v)
// in the map's. The rule needs triangles whose footprints cover the texel's whole square S: then the
// visible depth at every point of S is at most the depth of a triangle there, so a lit receiver is no
// deeper than the largest of their depths over S plus `tolerance` (the ground truth's ray offset),
// and with a query bias of at least `slack` any value from that depth less `slack` lights it. Else
// (S reaches a hole, a mesh's border, a silhouette fold or an edge-on triangle) lower stays the first
// hit.
//
// The cover is grown from the first-hit triangle across every edge that meets S (the square grown by
// a hundredth of a texel, for the footprints' float rounding) to the triangle on that edge's other
// side. It holds S when every such edge has exactly one such triangle, lying on the other side (not
// folded under), and the set stays small: the union's boundary then lies on edges that miss S (around
// a vertex in S the triangles form a closed, unfolded fan), and S, connected and holding the centre,
// lies inside it. docs/receiver-contracts.md, "The entry rule", has the argument.
constexpr int kMaxCoverTriangles = 24;  // more: lower stays the first hit (a bounded cost per texel)
float entry_lower_by_search(const TileGeometry& geometry, bool open, uint32_t first_prim, double cu, double cv,
                            double global_u, double global_v, float lower, float slack, float tolerance) {
  const auto& planes = open ? geometry.open_planes : geometry.closed_planes;
  const auto& vertices = open ? geometry.open_vertices : geometry.closed_vertices;
  const auto& neighbours = open ? geometry.open_neighbours : geometry.closed_neighbours;
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
  std::array<int32_t, kMaxCoverTriangles> cover;
  // The edge each triangle was reached across (-1: the first). Its test is skipped when the way back
  // is crossable too: met or not, it leads to a triangle already in the cover.
  std::array<int32_t, kMaxCoverTriangles> entered;
  cover[0] = int32_t(first_prim), entered[0] = -1;
  int count = 1;
  for (int i = 0; i < count; ++i) {
    const int32_t prim = cover[size_t(i)];
    if (planes[size_t(prim)].edge_on) return lower;
    const float* x = &vertices[size_t(prim) * 9];
    for (int k = 0; k < 3; ++k) {
      const EdgeNeighbour across = neighbours[size_t(prim)][size_t(k)];
      if (k == entered[size_t(i)] && across.crossable) continue;
      if (!edge_meets_square(x + 3 * k, x + 3 * ((k + 1) % 3))) continue;
      if (!across.crossable) return lower;  // none, edge-on, or folded under
      if (std::find(cover.begin(), cover.begin() + count, across.prim) != cover.begin() + count) continue;
      if (count == kMaxCoverTriangles) return lower;
      cover[size_t(count)] = across.prim, entered[size_t(count)] = across.edge;
      ++count;
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

}  // namespace

// The entry pass over a tile, in the common cases first: a square inside its first-hit triangle, or
// inside it and the triangle across the one edge that crosses it, or the two across the two edges
// that cross it near their shared vertex. These are the covers entry_lower_by_search would grow,
// but where its tests and these round apart, or where a crossed edge's line meets the square only
// beyond the edge's end (a thin triangle's tip), which the search would not cross: covers too, so
// sound (the same bytes as the search on the seven shared scenes at 16384^2).
// Per triangle, on the first texel that hits it: its edge lines and plane in global texel
// coordinates, and, when a square first crosses an edge, the triangle across it (when it lies on the
// other side, not folded) with that triangle's two other edge lines and plane. A square lies inside
// an edge's half-plane when the line's value at its centre exceeds the grown square's half-extent
// along the line's normal. Anything else goes to entry_lower_by_search.
class EntryCover::Fast {
 public:
  Fast(const TileGeometry& geometry, double tile_u0, double tile_v0)
      : geometry_(geometry), tile_u0_(tile_u0), tile_v0_(tile_v0) {}

  // For `count` squares of one row that share a first hit `key` (prim | open flag), centred at global
  // (gu_first + i, gv): the largest depth over each square of the cover found, NaN when neither
  // common case applies. The lines' and planes' v terms once per run.
  void deepest_run(uint32_t key, bool open, uint32_t prim, double gu_first, uint32_t count, double gv, double* out) {
    const double none = std::numeric_limits<double>::quiet_NaN();
    Entry& entry = entry_for(key, open, prim);
    if (!entry.triangle.usable) {
      std::fill(out, out + count, none);
      return;
    }
    const Triangle& triangle = entry.triangle;
    const RowLine edge[3] = {triangle.edge[0].at_row(gv), triangle.edge[1].at_row(gv), triangle.edge[2].at_row(gv)};
    const RowPlane own_plane = triangle.plane.at_row(gv);
    // Each edge's test is monotone in gu (its line's value is a chain of rounded, monotone steps), so
    // the squares inside all three are one range of the run: found from both ends, then not tested.
    auto inside = [&](uint32_t i) {
      const double gu = gu_first + i;
      return edge[0].holds(gu) && edge[1].holds(gu) && edge[2].holds(gu);
    };
    uint32_t inside_begin = 0, inside_end = count;
    while (inside_begin < count && !inside(inside_begin)) ++inside_begin;
    while (inside_end > inside_begin && !inside(inside_end - 1)) --inside_end;
    for (uint32_t i = inside_begin; i < inside_end; ++i) out[i] = own_plane.deepest(gu_first + i);
    for (uint32_t i = 0; i < count; ++i) {
      if (i == inside_begin) i = inside_end;  // (the range is empty only when inside_begin == count)
      if (i == count) break;
      const double gu = gu_first + i;
      const bool inside0 = edge[0].holds(gu), inside1 = edge[1].holds(gu), inside2 = edge[2].holds(gu);
      const double own = own_plane.deepest(gu);
      if (inside0 && inside1 && inside2) {  // the common case: the square inside its triangle
        out[i] = own;
        continue;
      }
      const int held = int(inside0) + int(inside1) + int(inside2);
      if (held == 2) {  // one edge crossed: the triangle across it
        out[i] = across_deepest(entry, inside0 ? (inside1 ? 2 : 1) : 0, open, prim, gu, gv, own);
        continue;
      }
      if (held == 1) {  // two edges crossed (near their shared vertex): the triangles across both
        const int kept = inside0 ? 0 : (inside1 ? 1 : 2);
        const double with_first = across_deepest(entry, (kept + 1) % 3, open, prim, gu, gv, own);
        out[i] = with_first == with_first ? across_deepest(entry, (kept + 2) % 3, open, prim, gu, gv, with_first)
                                          : none;
        continue;
      }
      out[i] = none;
    }
  }

 private:
  // A line and a plane on one row gv: b gv (dv gv) computed once, then the same sums as a gu + b gv + c.
  struct RowLine {
    double a, bv, c, margin;
    bool holds(double gu) const { return a * gu + bv + c > margin; }
  };
  struct RowPlane {
    double du, dvv, c, highest;
    double deepest(double gu) const { return std::min(du * gu + dvv + c, highest); }
  };
  struct Line {  // a (gu) + b (gv) + c, positive inside
    double a = 0, b = 0, c = 0, margin = 0;
    RowLine at_row(double gv) const { return {a, b * gv, c, margin}; }
  };
  struct Plane {  // the plane's largest depth over the square centred at (gu, gv), at most its deepest vertex
    double du = 0, dv = 0, c = 0, highest = 0;
    RowPlane at_row(double gv) const { return {du, dv * gv, c, highest}; }
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

  // A first hit's triangle, and the triangles across its edges, prepared on first use. A row
  // alternates between a few triangles (the two halves of a terrain quad), so a few are kept.
  struct Entry {
    uint32_t key = std::numeric_limits<uint32_t>::max();
    uint8_t across_ready = 0;  // bit k: across[k] is set
    Triangle triangle;
    Across across[3];
  };
  static constexpr unsigned kEntries = 8;

  Entry& entry_for(uint32_t key, bool open, uint32_t prim) {
    Entry& entry = entries_[(key * 0x9E3779B1u) >> 29];
    if (entry.key == key) return entry;
    entry.key = key;
    entry.across_ready = 0;
    const float* t;
    const double own = orientation(open, prim, &t);
    entry.triangle.usable = own != 0;
    if (!entry.triangle.usable) return entry;
    const auto& planes = open ? geometry_.open_planes : geometry_.closed_planes;
    for (int k = 0; k < 3; ++k) entry.triangle.edge[k] = line(t, k, own);
    entry.triangle.plane = plane_of(planes[prim]);
    return entry;
  }

  // max(`deepest`, the largest depth over the square at (gu, gv) of the triangle across edge k), or NaN
  // when there is none usable or the square is not inside its two other edges. With the square inside
  // the first hit's edges but k and at most one other, a point of the square beyond edge k's line lies
  // on the triangle across's side of their shared edge (it lies there, not folded under: crossable),
  // and inside its two other edges, so in it: each point of the square is in the first hit or in a
  // triangle across an edge whose line it is beyond.
  double across_deepest(Entry& entry, int k, bool open, uint32_t prim, double gu, double gv, double deepest) {
    const Across& across = across_of(entry, k, open, prim);
    if (!across.usable) return std::numeric_limits<double>::quiet_NaN();
    const RowLine a0 = across.edge[0].at_row(gv), a1 = across.edge[1].at_row(gv);
    return a0.holds(gu) && a1.holds(gu) ? std::max(deepest, across.plane.at_row(gv).deepest(gu))
                                        : std::numeric_limits<double>::quiet_NaN();
  }

  const Across& across_of(Entry& entry, int k, bool open, uint32_t prim) {
    Across& across = entry.across[k];
    if (entry.across_ready & (1u << k)) return across;
    entry.across_ready |= uint8_t(1u << k);
    const EdgeNeighbour n = (open ? geometry_.open_neighbours : geometry_.closed_neighbours)[prim][size_t(k)];
    const float* o;
    const double theirs = n.prim < 0 ? 0 : orientation(open, uint32_t(n.prim), &o);
    across.usable = theirs != 0 && n.crossable;
    if (!across.usable) return across;
    across.edge[0] = line(o, (n.edge + 1) % 3, theirs);
    across.edge[1] = line(o, (n.edge + 2) % 3, theirs);
    across.plane = plane_of((open ? geometry_.open_planes : geometry_.closed_planes)[size_t(n.prim)]);
    return across;
  }

  const TileGeometry& geometry_;
  double tile_u0_, tile_v0_;
  Entry entries_[kEntries];
};

EntryCover::EntryCover(const TileGeometry& geometry, TileCoord tile, uint32_t tile_size,
                       float slack, float tolerance)
    : geometry_(geometry),
      tile_u0_(double(tile.x) * tile_size),
      tile_v0_(double(tile.y) * tile_size),
      slack_(slack),
      tolerance_(tolerance),
      fast_(std::make_unique<Fast>(geometry, tile_u0_, tile_v0_)) {}

EntryCover::~EntryCover() = default;

void EntryCover::bound_row(uint32_t v, std::span<const uint32_t> first_hits, std::span<const DepthInterval> row,
                           std::span<float> entry_lower) {
  const double gv = tile_v0_ + v + 0.5;
  const uint32_t size = uint32_t(row.size());
  run_deepest_.resize(size);
  for (uint32_t u = 0; u < size;) {
    if (row[u].lower >= 1.0f) {
      ++u;
      continue;
    }
    const uint32_t key = first_hits[u];
    uint32_t end = u + 1;
    while (end < size && row[end].lower < 1.0f && first_hits[end] == key) ++end;
    const bool open = (key & kOpenFlag) != 0;
    const uint32_t prim = key & ~kOpenFlag;
    fast_->deepest_run(key, open, prim, tile_u0_ + u + 0.5, end - u, gv, run_deepest_.data());
    bool searched = false;
    for (uint32_t w = u; w < end; ++w) {
      const double deepest = run_deepest_[w - u];
      if (deepest == deepest) {
        entry_lower[w] = entry_bound(deepest, row[w].lower, slack_, tolerance_);
      } else {
        searches_.push_back({w, key});
        searched = true;
      }
    }
    if (searched) prefetch_triangle(open, prim);
    u = end;
  }
  // The searches after the row's runs, their triangles fetched ahead: a search walks a vertex's fan
  // through the neighbour lists, and a cold triangle stalls it.
  constexpr size_t kAhead = 4;
  for (size_t j = 0; j < searches_.size(); ++j) {
    if (j + kAhead < searches_.size()) {
      const uint32_t ahead = searches_[j + kAhead].key;
      const bool ahead_open = (ahead & kOpenFlag) != 0;
      const auto& neighbours = ahead_open ? geometry_.open_neighbours : geometry_.closed_neighbours;
      for (const EdgeNeighbour& n : neighbours[ahead & ~kOpenFlag])
        if (n.prim >= 0) prefetch_triangle(ahead_open, uint32_t(n.prim));
    }
    const auto [w, key] = searches_[j];
    entry_lower[w] = entry_lower_by_search(geometry_, (key & kOpenFlag) != 0, key & ~kOpenFlag, w + 0.5, v + 0.5,
                                           tile_u0_ + w + 0.5, gv, row[w].lower, slack_, tolerance_);
  }
  searches_.clear();
}

void EntryCover::prefetch_triangle(bool open, uint32_t prim) const {
  const float* vertices = &(open ? geometry_.open_vertices : geometry_.closed_vertices)[size_t(prim) * 9];
  __builtin_prefetch(vertices);
  __builtin_prefetch(vertices + 8);
  __builtin_prefetch(&(open ? geometry_.open_planes : geometry_.closed_planes)[prim]);
  __builtin_prefetch(&(open ? geometry_.open_neighbours : geometry_.closed_neighbours)[prim]);
}

}  // namespace shadowtiles
