#include "builder/reference_entry_bounds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace shadowtiles {

namespace {

using Point = std::array<double, 3>;  // tile-local u, v and depth

// Barycentric weights of (pu, pv) in triangle (a, b, c); false when the triangle is edge-on.
bool weights(const Point& a, const Point& b, const Point& c, double pu, double pv, double w[3]) {
  const double area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  if (area == 0) return false;
  w[0] = ((b[0] - pu) * (c[1] - pv) - (b[1] - pv) * (c[0] - pu)) / area;
  w[1] = ((c[0] - pu) * (a[1] - pv) - (c[1] - pv) * (a[0] - pu)) / area;
  w[2] = ((a[0] - pu) * (b[1] - pv) - (a[1] - pv) * (b[0] - pu)) / area;
  return true;
}

// Depth of the closed triangle at (pu, pv), or false when the point is outside it.
bool depth_in(const Point& a, const Point& b, const Point& c, double pu, double pv, double* depth) {
  double w[3];
  if (!weights(a, b, c, pu, pv, w) || w[0] < 0 || w[1] < 0 || w[2] < 0) return false;
  *depth = w[0] * a[2] + w[1] * b[2] + w[2] * c[2];
  return true;
}

// The squares covered by two triangles sharing the edge (p, q) (welded vertex ids), and the largest
// depth over each; keeps the smallest bound per texel in `deepest`.
template <typename Local, typename Triangle>
void cover_by_pair(const Local& local, const Triangle& first, const Triangle& second, uint32_t p, uint32_t q,
                   uint32_t size, std::vector<double>& deepest) {
  auto opposite_of = [&](const Triangle& t) {
    for (int k = 0; k < 3; ++k)
      if (t[k] != p && t[k] != q) return t[k];
    return t[0];
  };
  const Point a = local(p), b = local(q), s = local(opposite_of(first)), o = local(opposite_of(second));
  // Which side of the line a -> b a point is on (> 0: the first triangle's side).
  auto side_raw = [&](double pu, double pv) { return (b[0] - a[0]) * (pv - a[1]) - (b[1] - a[1]) * (pu - a[0]); };
  const double first_side = side_raw(s[0], s[1]);
  if (first_side == 0 || side_raw(o[0], o[1]) * first_side >= 0) return;  // edge-on, or folded under
  auto side = [&](double pu, double pv) { return side_raw(pu, pv) * (first_side > 0 ? 1.0 : -1.0); };
  const double lo_u = std::ceil(std::min({a[0], b[0], s[0], o[0]})), hi_u = std::floor(std::max({a[0], b[0], s[0], o[0]}));
  const double lo_v = std::ceil(std::min({a[1], b[1], s[1], o[1]})), hi_v = std::floor(std::max({a[1], b[1], s[1], o[1]}));
  const int64_t first_u = int64_t(std::max(0.0, lo_u)), last_u = int64_t(std::min(double(size), hi_u)) - 1;
  const int64_t first_v = int64_t(std::max(0.0, lo_v)), last_v = int64_t(std::min(double(size), hi_v)) - 1;
  const double edge_u = b[0] - a[0], edge_v = b[1] - a[1], edge_length2 = edge_u * edge_u + edge_v * edge_v;
  for (int64_t v = first_v; v <= last_v; ++v)
    for (int64_t u = first_u; u <= last_u; ++u) {
      const double cu[4] = {double(u), double(u + 1), double(u + 1), double(u)};  // around the square
      const double cv[4] = {double(v), double(v), double(v + 1), double(v + 1)};
      double corner_side[4];
      double bound = -std::numeric_limits<double>::infinity(), depth;
      bool covered = true;
      for (int c = 0; c < 4 && covered; ++c) {
        corner_side[c] = side(cu[c], cv[c]);
        covered = corner_side[c] >= 0 ? depth_in(a, b, s, cu[c], cv[c], &depth) : depth_in(a, b, o, cu[c], cv[c], &depth);
        bound = std::max(bound, depth);
      }
      // Where a side of the square crosses the line, the crossing must lie on the edge.
      for (int c = 0; c < 4 && covered; ++c) {
        const int d = (c + 1) % 4;
        if (!((corner_side[c] > 0 && corner_side[d] < 0) || (corner_side[c] < 0 && corner_side[d] > 0))) continue;
        const double f = corner_side[c] / (corner_side[c] - corner_side[d]);
        const double pu = cu[c] + f * (cu[d] - cu[c]), pv = cv[c] + f * (cv[d] - cv[c]);
        const double along = ((pu - a[0]) * edge_u + (pv - a[1]) * edge_v) / edge_length2;
        covered = along >= -1e-12 && along <= 1 + 1e-12;
        bound = std::max(bound, a[2] + std::clamp(along, 0.0, 1.0) * (b[2] - a[2]));
      }
      if (!covered) continue;
      double& best = deepest[size_t(v) * size + size_t(u)];
      best = std::min(best, bound);
    }
}

}  // namespace

std::vector<float> reference_entry_bounds(const LightSpaceScene& scene, TileCoord tile, const TileIntervals& first_hits,
                                          double slack, double tolerance) {
  const uint32_t size = first_hits.size;
  const double u0 = double(tile.x) * scene.layout().tile_size(), v0 = double(tile.y) * scene.layout().tile_size();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> deepest(first_hits.texels.size(), inf);  // smallest deepest corner of a covering triangle
  const Scene& world = scene.scene();
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    // Tile-local texel coordinates, depth as is.
    const LightSpacePoint& pa = scene.vertex(tri[0]);
    const LightSpacePoint& pb = scene.vertex(tri[1]);
    const LightSpacePoint& pc = scene.vertex(tri[2]);
    const double au = pa.u - u0, av = pa.v - v0, bu = pb.u - u0, bv = pb.v - v0, cu = pc.u - u0, cv = pc.v - v0;
    const double area = (bu - au) * (cv - av) - (bv - av) * (cu - au);
    if (area == 0) continue;  // edge-on: covers no square
    // Squares whose four corners lie in the triangle's bounding box.
    const double lo_u = std::ceil(std::min({au, bu, cu})), hi_u = std::floor(std::max({au, bu, cu}));
    const double lo_v = std::ceil(std::min({av, bv, cv})), hi_v = std::floor(std::max({av, bv, cv}));
    const int64_t first_u = int64_t(std::max(0.0, lo_u)), last_u = int64_t(std::min(double(size), hi_u)) - 1;
    const int64_t first_v = int64_t(std::max(0.0, lo_v)), last_v = int64_t(std::min(double(size), hi_v)) - 1;
    // Barycentric weights (times the area) of a point; the point is in the closed triangle when all
    // three have the area's sign or are zero.
    auto depth_if_inside = [&](double pu, double pv, double* depth) {
      const double wa = ((bu - pu) * (cv - pv) - (bv - pv) * (cu - pu)) / area;
      const double wb = ((cu - pu) * (av - pv) - (cv - pv) * (au - pu)) / area;
      const double wc = ((au - pu) * (bv - pv) - (av - pv) * (bu - pu)) / area;
      if (wa < 0 || wb < 0 || wc < 0) return false;
      *depth = wa * pa.depth + wb * pb.depth + wc * pc.depth;
      return true;
    };
    for (int64_t v = first_v; v <= last_v; ++v)
      for (int64_t u = first_u; u <= last_u; ++u) {
        double corner_max = -inf, depth;
        bool covered = true;
        for (int dv = 0; dv <= 1 && covered; ++dv)
          for (int du = 0; du <= 1 && covered; ++du) {
            covered = depth_if_inside(double(u + du), double(v + dv), &depth);
            corner_max = std::max(corner_max, depth);
          }
        if (!covered) continue;
        double& best = deepest[size_t(v) * size + size_t(u)];
        best = std::min(best, corner_max);
      }
  }
  // Pairs of triangles that share an edge (welded vertex ids) and lie on its two sides: their union
  // covers a square when the part of the square on each side of the edge's line lies in that side's
  // closed triangle. The parts are convex, so it is enough that their vertices do: the square's
  // corners on that side and the points where its sides cross the line, which must lie on the edge.
  // The bound is the largest depth at those vertices (each triangle's over its own part).
  std::vector<std::pair<uint64_t, uint32_t>> edges;  // (edge key, triangle)
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const uint64_t a = tri[k], b = tri[(k + 1) % 3];
      edges.push_back({std::min(a, b) << 32 | std::max(a, b), t});
    }
  }
  std::sort(edges.begin(), edges.end());
  auto local = [&](uint32_t id) {
    const LightSpacePoint& p = scene.vertex(id);
    return std::array<double, 3>{p.u - u0, p.v - v0, p.depth};
  };
  for (size_t i = 0; i < edges.size();) {
    size_t end = i + 1;
    while (end < edges.size() && edges[end].first == edges[i].first) ++end;
    for (size_t x = i; x < end; ++x)
      for (size_t y = x + 1; y < end; ++y)
        cover_by_pair(local, world.triangles[edges[x].second], world.triangles[edges[y].second],
                      uint32_t(edges[i].first >> 32), uint32_t(edges[i].first), size, deepest);
    i = end;
  }
  std::vector<float> bounds(first_hits.texels.size());
  for (size_t i = 0; i < bounds.size(); ++i) {
    const float first = first_hits.texels[i].lower;
    bounds[i] = first;
    if (first >= 1.0f || deepest[i] == inf) continue;
    const double entry = deepest[i] + tolerance - slack;
    if (entry >= double(first)) continue;
    float bound = float(entry);
    if (double(bound) < entry) bound = std::nextafter(bound, std::numeric_limits<float>::infinity());
    bounds[i] = std::max(0.0f, bound);
  }
  return bounds;
}

}  // namespace shadowtiles
