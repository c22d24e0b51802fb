#include "builder/tile_coverage_estimate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace shadowtiles {

TileFootprint estimate_tile_footprint(const LightSpaceScene& scene, TileCoord tile) {
  const uint32_t size = scene.layout().tile_size();
  const uint32_t grid = std::min(kCoverageGrid, size);
  const double cell = double(size) / grid;  // texels per cell side
  const double u0 = double(tile.x) * size, v0 = double(tile.y) * size;
  constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  // Nearest triangle and its depth at each cell centre (kNone: nothing covers it).
  std::array<uint32_t, kCoverageGrid * kCoverageGrid> front;
  std::array<double, kCoverageGrid * kCoverageGrid> depth;
  // The front triangle's depth plane at each cell: depth = z0 + du * (u - u_c) + dv * (v - v_c) in cells.
  std::array<std::array<double, 2>, kCoverageGrid * kCoverageGrid> slope{};
  front.fill(kNone);
  depth.fill(std::numeric_limits<double>::infinity());
  TileFootprint out;
  double du = 0, dv = 0;  // the current triangle's depth gradient per cell
  auto keep_nearest = [&](size_t at, uint32_t t, double d) {
    if (d < depth[at] || (d == depth[at] && t < front[at])) {  // ties: lowest index, order-independent
      depth[at] = d;
      front[at] = t;
      slope[at] = {du, dv};
    }
  };
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = scene.scene().triangles[t];
    double u[3], v[3], z[3];  // u, v in cells, relative to the tile
    for (int k = 0; k < 3; ++k) {
      const LightSpacePoint& p = scene.vertex(tri[k]);
      u[k] = (p.u - u0) / cell;
      v[k] = (p.v - v0) / cell;
      z[k] = p.depth;
    }
    // Cells whose centre (i + 0.5, j + 0.5) may lie inside the footprint.
    auto first = [&](double lo) { return int(std::clamp(std::ceil(lo - 0.5), 0.0, double(grid))); };
    auto last = [&](double hi) { return int(std::clamp(std::floor(hi - 0.5), -1.0, double(grid) - 1)); };
    int i0 = first(std::min({u[0], u[1], u[2]})), i1 = last(std::max({u[0], u[1], u[2]}));
    int j0 = first(std::min({v[0], v[1], v[2]})), j1 = last(std::max({v[0], v[1], v[2]}));
    double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    double s = area >= 0 ? 1 : -1;  // either winding
    du = dv = 0;
    if (area != 0) {  // the plane through the three vertices, in depth per cell
      du = ((z[1] - z[0]) * (v[2] - v[0]) - (z[2] - z[0]) * (v[1] - v[0])) / area;
      dv = ((z[2] - z[0]) * (u[1] - u[0]) - (z[1] - z[0]) * (u[2] - u[0])) / area;
    }
    bool marked = false;
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        double pu = i + 0.5, pv = j + 0.5;
        double e0 = s * ((u[1] - u[0]) * (pv - v[0]) - (v[1] - v[0]) * (pu - u[0]));
        double e1 = s * ((u[2] - u[1]) * (pv - v[1]) - (v[2] - v[1]) * (pu - u[1]));
        double e2 = s * ((u[0] - u[2]) * (pv - v[2]) - (v[0] - v[2]) * (pu - u[2]));
        if (e0 >= 0 && e1 >= 0 && e2 >= 0) {
          // Depth by barycentric weights (e0 faces vertex 2, e1 vertex 0, e2 vertex 1).
          const double sum = e0 + e1 + e2;
          const double d = sum > 0 ? (e1 * z[0] + e2 * z[1] + e0 * z[2]) / sum : std::min({z[0], z[1], z[2]});
          keep_nearest(size_t(j) * grid + size_t(i), t, d);
          ++out.layered_cells;
          marked = true;
        }
      }
    }
    if (!marked) {
      ++out.sub_cell_triangles;
      if (u[0] >= 0 && u[0] < grid && v[0] >= 0 && v[0] < grid)
        keep_nearest(size_t(v[0]) * grid + size_t(u[0]), t, z[0]);
    }
  }
  std::vector<uint32_t> seen;
  for (uint32_t j = 0; j < grid; ++j) {
    for (uint32_t i = 0; i < grid; ++i) {
      const uint32_t here = front[size_t(j) * grid + i];
      if (here == kNone) continue;
      ++out.covered_cells;
      seen.push_back(here);
    }
  }
  // Two neighbouring cells see one plane when each one's plane predicts the other's depth (to a
  // thousandth of the depth change across a cell: seams of a triangulated flat polygon pass, float
  // rounding of the vertices included; creases and steps do not).
  auto coplanar = [&](size_t a, size_t b, double step_u, double step_v) {
    const double reach = std::max(std::abs(slope[a][0]) + std::abs(slope[a][1]), std::abs(slope[b][0]) + std::abs(slope[b][1]));
    const double tolerance = 1e-3 * reach + 1e-12;
    const double from_a = depth[a] + slope[a][0] * step_u + slope[a][1] * step_v;
    const double from_b = depth[b] - slope[b][0] * step_u - slope[b][1] * step_v;
    return std::abs(from_a - depth[b]) <= tolerance && std::abs(from_b - depth[a]) <= tolerance;
  };
  auto edge = [&](size_t a, size_t b, double step_u, double step_v) {
    if (front[a] == front[b]) return;
    ++out.triangle_edges;
    if (front[a] == kNone || front[b] == kNone || !coplanar(a, b, step_u, step_v)) ++out.plane_edges;
  };
  for (uint32_t j = 0; j < grid; ++j) {
    for (uint32_t i = 0; i < grid; ++i) {
      const size_t here = size_t(j) * grid + i;
      if (i + 1 < grid) edge(here, here + 1, 1, 0);
      if (j + 1 < grid) edge(here, here + grid, 0, 1);
    }
  }
  std::sort(seen.begin(), seen.end());
  out.visible_triangles = uint64_t(std::unique(seen.begin(), seen.end()) - seen.begin());
  out.covered_texels = uint64_t(std::llround(double(out.covered_cells) * cell * cell));
  return out;
}

}  // namespace shadowtiles
