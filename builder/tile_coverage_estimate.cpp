#include "builder/tile_coverage_estimate.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>

namespace shadowtiles {

uint64_t estimate_covered_texels(const LightSpaceScene& scene, TileCoord tile) {
  const uint32_t size = scene.layout().tile_size();
  const uint32_t grid = std::min(kCoverageGrid, size);
  const double cell = double(size) / grid;  // texels per cell side
  const double u0 = double(tile.x) * size, v0 = double(tile.y) * size;
  std::bitset<kCoverageGrid * kCoverageGrid> covered;
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = scene.scene().triangles[t];
    double u[3], v[3];  // in cells, relative to the tile
    for (int k = 0; k < 3; ++k) {
      const LightSpacePoint& p = scene.vertex(tri[k]);
      u[k] = (p.u - u0) / cell;
      v[k] = (p.v - v0) / cell;
    }
    // Cells whose centre (i + 0.5, j + 0.5) may lie inside the footprint.
    auto first = [&](double lo) { return int(std::clamp(std::ceil(lo - 0.5), 0.0, double(grid))); };
    auto last = [&](double hi) { return int(std::clamp(std::floor(hi - 0.5), -1.0, double(grid) - 1)); };
    int i0 = first(std::min({u[0], u[1], u[2]})), i1 = last(std::max({u[0], u[1], u[2]}));
    int j0 = first(std::min({v[0], v[1], v[2]})), j1 = last(std::max({v[0], v[1], v[2]}));
    double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    double s = area >= 0 ? 1 : -1;  // either winding
    bool marked = false;
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        double pu = i + 0.5, pv = j + 0.5;
        double e0 = s * ((u[1] - u[0]) * (pv - v[0]) - (v[1] - v[0]) * (pu - u[0]));
        double e1 = s * ((u[2] - u[1]) * (pv - v[1]) - (v[2] - v[1]) * (pu - u[1]));
        double e2 = s * ((u[0] - u[2]) * (pv - v[2]) - (v[0] - v[2]) * (pu - u[2]));
        if (e0 >= 0 && e1 >= 0 && e2 >= 0) {
          covered.set(size_t(j) * grid + size_t(i));
          marked = true;
        }
      }
    }
    if (!marked && u[0] >= 0 && u[0] < grid && v[0] >= 0 && v[0] < grid)
      covered.set(size_t(v[0]) * grid + size_t(u[0]));
  }
  const double texels_per_cell = cell * cell;
  return uint64_t(std::llround(double(covered.count()) * texels_per_cell));
}

}  // namespace shadowtiles
