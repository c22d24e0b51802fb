#include "builder/receiver_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace shadowtiles {

std::vector<Receiver> sample_receivers(const Scene& scene, size_t count, uint64_t seed) {
  std::vector<Receiver> receivers;
  if (scene.triangles.empty() || count == 0) return receivers;
  std::vector<double> cumulative_area(scene.triangles.size());
  std::vector<Vec3> normals(scene.triangles.size());
  double total = 0;
  for (size_t t = 0; t < scene.triangles.size(); ++t) {
    const Vec3& a = scene.vertices[scene.triangles[t][0]];
    const Vec3& b = scene.vertices[scene.triangles[t][1]];
    const Vec3& c = scene.vertices[scene.triangles[t][2]];
    Vec3 e1{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    Vec3 n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    total += 0.5 * length;
    cumulative_area[t] = total;
    normals[t] = length > 0 ? Vec3{n[0] / length, n[1] / length, n[2] / length} : Vec3{0, 0, 1};
  }
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  receivers.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    double pick = unit(random) * total;
    size_t t = size_t(std::lower_bound(cumulative_area.begin(), cumulative_area.end(), pick) - cumulative_area.begin());
    t = std::min(t, scene.triangles.size() - 1);
    double r1 = unit(random), r2 = unit(random);
    if (r1 + r2 > 1) { r1 = 1 - r1; r2 = 1 - r2; }
    const Vec3& a = scene.vertices[scene.triangles[t][0]];
    const Vec3& b = scene.vertices[scene.triangles[t][1]];
    const Vec3& c = scene.vertices[scene.triangles[t][2]];
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = a[k] + r1 * (b[k] - a[k]) + r2 * (c[k] - a[k]);
    receivers.push_back({p, normals[t], uint32_t(t)});
  }
  return receivers;
}

}  // namespace shadowtiles
