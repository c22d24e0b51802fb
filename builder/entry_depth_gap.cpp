#include "builder/entry_depth_gap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "builder/entry_cover.hpp"

namespace shadowtiles {
namespace {

// As the cover pass: footprints are tile-local floats, so a triangle meets the square when it meets
// the square grown by a hundredth of a texel.
constexpr double kGrownHalf = 0.51;
// Depth bounds from the double planes are exact up to rounding; this much lower keeps a triangle
// whose shallowest point is exactly at the gap's edge in the set (more triangles only raise B).
constexpr double kRoundingSlack = 1e-9;

struct Candidate {
  uint32_t u;
  double deepest;  // B so far: the largest depth over the square of the triangles within the gap
};

}  // namespace

void lower_entry_bounds_by_depth_gaps(const TileGeometry& geometry, TileCoord tile, uint32_t size,
                                      std::span<const DepthInterval> texels, std::span<float> entry_lower, float gap,
                                      float slack, float tolerance) {
  // The texels still at their first hit, row by row.
  std::vector<uint32_t> row_begin(size_t(size) + 1, 0);
  std::vector<Candidate> candidates;
  for (uint32_t v = 0; v < size; ++v) {
    row_begin[v] = uint32_t(candidates.size());
    for (uint32_t u = 0; u < size; ++u) {
      const size_t i = size_t(v) * size + u;
      if (texels[i].lower < 1.0f && entry_lower[i] >= texels[i].lower)
        candidates.push_back({u, -std::numeric_limits<double>::infinity()});
    }
  }
  row_begin[size] = uint32_t(candidates.size());
  if (candidates.empty()) return;

  const double tile_u0 = double(tile.x) * size, tile_v0 = double(tile.y) * size;
  auto visit = [&](const std::vector<float>& vertices, const std::vector<DepthPlane>& planes) {
    for (size_t t = 0; t < planes.size(); ++t) {
      const float* x = &vertices[t * 9];
      const DepthPlane& plane = planes[t];
      const double u_min = std::min({x[0], x[3], x[6]}), u_max = std::max({x[0], x[3], x[6]});
      const double v_min = std::min({x[1], x[4], x[7]}), v_max = std::max({x[1], x[4], x[7]});
      // Texels whose grown square meets the footprint's box: centre u + 0.5 within kGrownHalf of it.
      const double first_u = std::ceil(u_min - 0.5 - kGrownHalf), last_u = std::floor(u_max - 0.5 + kGrownHalf);
      const double first_v = std::ceil(v_min - 0.5 - kGrownHalf), last_v = std::floor(v_max - 0.5 + kGrownHalf);
      if (last_u < 0 || last_v < 0 || first_u >= size || first_v >= size) continue;
      const uint32_t u0 = uint32_t(std::max(first_u, 0.0)), u1 = uint32_t(std::min(last_u, double(size - 1)));
      const uint32_t v0 = uint32_t(std::max(first_v, 0.0)), v1 = uint32_t(std::min(last_v, double(size - 1)));
      // Edge lines, positive inside, for the separating-edge test (none for an edge-on footprint,
      // whose box alone decides).
      const double area = (double(x[3]) - x[0]) * (double(x[7]) - x[1]) - (double(x[4]) - x[1]) * (double(x[6]) - x[0]);
      const double orientation = area > 0 ? 1.0 : area < 0 ? -1.0 : 0.0;
      double line_a[3], line_b[3], line_c[3], line_margin[3];
      for (int k = 0; k < 3; ++k) {
        const float* p = x + 3 * k;
        const float* q = x + 3 * ((k + 1) % 3);
        const double a = -(double(q[1]) - p[1]), b = double(q[0]) - p[0];
        line_a[k] = orientation * a;
        line_b[k] = orientation * b;
        line_c[k] = -orientation * (a * p[0] + b * p[1]);
        line_margin[k] = -kGrownHalf * (std::fabs(a) + std::fabs(b));
      }
      const double half_slope = plane.edge_on ? 0.0 : 0.5 * (std::fabs(plane.du) + std::fabs(plane.dv));
      for (uint32_t v = v0; v <= v1; ++v) {
        auto begin = candidates.begin() + row_begin[v], end = candidates.begin() + row_begin[v + 1];
        auto it = std::lower_bound(begin, end, u0, [](const Candidate& c, uint32_t u) { return c.u < u; });
        const double cv = v + 0.5;
        for (; it != end && it->u <= u1; ++it) {
          const double cu = it->u + 0.5;
          if (orientation != 0) {
            bool apart = false;
            for (int k = 0; k < 3 && !apart; ++k)
              apart = line_a[k] * cu + line_b[k] * cv + line_c[k] < line_margin[k];
            if (apart) continue;
          }
          // The triangle's depth range over the (exact) square: its plane's there, within its
          // vertices' range. Edge-on: the vertices' range.
          double shallowest = plane.lowest, deepest = plane.highest;
          if (!plane.edge_on) {
            const double centre =
                plane.depth + plane.du * (tile_u0 + cu - plane.u) + plane.dv * (tile_v0 + cv - plane.v);
            shallowest = std::max(shallowest, centre - half_slope);
            deepest = std::min(deepest, centre + half_slope);
          }
          const float first = texels[size_t(v) * size + it->u].lower;
          if (shallowest - kRoundingSlack <= double(first) + double(gap)) it->deepest = std::max(it->deepest, deepest);
        }
      }
    }
  };
  visit(geometry.closed_vertices, geometry.closed_planes);
  visit(geometry.open_vertices, geometry.open_planes);

  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t c = row_begin[v]; c < row_begin[v + 1]; ++c) {
      const size_t i = size_t(v) * size + candidates[c].u;
      // The first-hit triangle is always within the gap, so B is finite.
      if (candidates[c].deepest == -std::numeric_limits<double>::infinity()) continue;
      entry_lower[i] = std::min(entry_lower[i], entry_bound(candidates[c].deepest, texels[i].lower, slack, tolerance));
    }
}

}  // namespace shadowtiles
