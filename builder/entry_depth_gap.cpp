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

// A triangle's depth range over a texel's (exact) square, centre (gu, gv) in global texels: its
// plane's there, within its vertices' range; edge-on, the vertices' range.
struct DepthRange {
  double shallowest, deepest;
};
DepthRange range_over_square(const DepthPlane& plane, double gu, double gv) {
  if (plane.edge_on) return {plane.lowest, plane.highest};
  const double centre = plane.depth + plane.du * (gu - plane.u) + plane.dv * (gv - plane.v);
  const double half_slope = 0.5 * (std::fabs(plane.du) + std::fabs(plane.dv));
  return {std::max(plane.lowest, centre - half_slope), std::min(plane.highest, centre + half_slope)};
}

}  // namespace

bool gap_may_lower(const DepthPlane& plane, double gu, double gv, float lower, float slack, float tolerance) {
  return entry_bound(range_over_square(plane, gu, gv).deepest, lower, slack, tolerance) < lower;
}

void lower_entry_bounds_by_depth_gaps(const TileGeometry& geometry, TileCoord tile, uint32_t size,
                                      std::span<const DepthInterval> texels, std::span<const uint32_t> candidate_texels,
                                      std::span<float> entry_lower, float gap, float slack, float tolerance) {
  if (candidate_texels.empty()) return;
  // The candidates row by row.
  std::vector<uint32_t> row_begin(size_t(size) + 1, 0);
  std::vector<Candidate> candidates;
  candidates.reserve(candidate_texels.size());
  for (uint32_t i : candidate_texels) {
    ++row_begin[i / size + 1];
    candidates.push_back({i % size, -std::numeric_limits<double>::infinity()});
  }
  for (uint32_t v = 0; v < size; ++v) row_begin[v + 1] += row_begin[v];
  // One bit per texel: most triangles have no candidate under their box, which a few words tell.
  const size_t words_per_row = (size_t(size) + 63) / 64;
  std::vector<uint64_t> marked(words_per_row * size, 0);
  for (uint32_t i : candidate_texels) marked[size_t(i / size) * words_per_row + (i % size) / 64] |= uint64_t(1) << (i % size % 64);
  auto any_marked = [&](uint32_t v, uint32_t u0, uint32_t u1) {
    const uint64_t* row = &marked[size_t(v) * words_per_row];
    for (uint32_t w = u0 / 64; w <= u1 / 64; ++w) {
      uint64_t bits = row[w];
      if (w == u0 / 64) bits &= ~uint64_t(0) << (u0 % 64);
      if (w == u1 / 64 && u1 % 64 != 63) bits &= (uint64_t(1) << (u1 % 64 + 1)) - 1;
      if (bits) return true;
    }
    return false;
  };

  const double tile_u0 = double(tile.x) * size, tile_v0 = double(tile.y) * size;
  auto visit = [&](const std::vector<float>& vertices, const std::vector<DepthPlane>& planes) {
    for (size_t t = 0; t < planes.size(); ++t) {
      const float* x = &vertices[t * 9];
      const double u_min = std::min({x[0], x[3], x[6]}), u_max = std::max({x[0], x[3], x[6]});
      const double v_min = std::min({x[1], x[4], x[7]}), v_max = std::max({x[1], x[4], x[7]});
      // Texels whose grown square meets the footprint's box: centre u + 0.5 within kGrownHalf of it.
      const double first_u = std::ceil(u_min - 0.5 - kGrownHalf), last_u = std::floor(u_max - 0.5 + kGrownHalf);
      const double first_v = std::ceil(v_min - 0.5 - kGrownHalf), last_v = std::floor(v_max - 0.5 + kGrownHalf);
      if (last_u < 0 || last_v < 0 || first_u >= size || first_v >= size) continue;
      const uint32_t u0 = uint32_t(std::max(first_u, 0.0)), u1 = uint32_t(std::min(last_u, double(size - 1)));
      const uint32_t v0 = uint32_t(std::max(first_v, 0.0)), v1 = uint32_t(std::min(last_v, double(size - 1)));
      if (row_begin[v0] == row_begin[size_t(v1) + 1]) continue;  // no candidate in the box's rows
      const DepthPlane& plane = planes[t];
      // Edge lines, positive inside, for the separating-edge test (none for an edge-on footprint,
      // whose box alone decides); set up at the first candidate under the box.
      double orientation = 0, line_a[3] = {}, line_b[3] = {}, line_c[3] = {}, line_margin[3] = {};
      bool lines_ready = false;
      auto prepare_lines = [&] {
        const double area =
            (double(x[3]) - x[0]) * (double(x[7]) - x[1]) - (double(x[4]) - x[1]) * (double(x[6]) - x[0]);
        orientation = area > 0 ? 1.0 : area < 0 ? -1.0 : 0.0;
        for (int k = 0; k < 3; ++k) {
          const float* p = x + 3 * k;
          const float* q = x + 3 * ((k + 1) % 3);
          const double a = -(double(q[1]) - p[1]), b = double(q[0]) - p[0];
          line_a[k] = orientation * a;
          line_b[k] = orientation * b;
          line_c[k] = -orientation * (a * p[0] + b * p[1]);
          line_margin[k] = -kGrownHalf * (std::fabs(a) + std::fabs(b));
        }
        lines_ready = true;
      };
      for (uint32_t v = v0; v <= v1; ++v) {
        if (row_begin[v] == row_begin[v + 1] || !any_marked(v, u0, u1)) continue;
        if (!lines_ready) prepare_lines();
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
          const auto [shallowest, deepest] = range_over_square(plane, tile_u0 + cu, tile_v0 + cv);
          const float first = texels[size_t(v) * size + it->u].lower;
          if (shallowest - kRoundingSlack <= double(first) + double(gap)) it->deepest = std::max(it->deepest, deepest);
        }
      }
    }
  };
  visit(geometry.closed_vertices, geometry.closed_planes);
  visit(geometry.open_vertices, geometry.open_planes);

  for (size_t c = 0; c < candidates.size(); ++c) {
    const size_t i = candidate_texels[c];
    // The first-hit triangle is always within the gap, so B is finite.
    if (candidates[c].deepest == -std::numeric_limits<double>::infinity()) continue;
    entry_lower[i] = std::min(entry_lower[i], entry_bound(candidates[c].deepest, texels[i].lower, slack, tolerance));
  }
}

}  // namespace shadowtiles
