#include "builder/reference_entry_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shadowtiles {

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
