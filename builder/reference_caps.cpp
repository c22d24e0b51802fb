#include "builder/reference_caps.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "builder/second_layer_rule.hpp"

namespace shadowtiles {
namespace {

using Point = std::array<double, 3>;  // u, v, depth
using Poly = std::vector<Point>;

// Keeps where a*u + b*v + c*depth + d >= 0.
void cut(Poly& poly, Poly& scratch, double a, double b, double c, double d) {
  scratch.clear();
  const size_t n = poly.size();
  for (size_t k = 0; k < n; ++k) {
    const Point& p = poly[k];
    const Point& q = poly[(k + 1) % n];
    const double fp = a * p[0] + b * p[1] + c * p[2] + d;
    const double fq = a * q[0] + b * q[1] + c * q[2] + d;
    if (fp >= 0) scratch.push_back(p);
    if ((fp >= 0) != (fq >= 0)) {
      const double t = fp / (fp - fq);
      scratch.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), p[2] + t * (q[2] - p[2])});
    }
  }
  poly.swap(scratch);
}

double shallowest(const Poly& poly) {
  double z = std::numeric_limits<double>::infinity();
  for (const Point& p : poly) z = std::min(z, p[2]);
  return z;
}

struct Triangle {
  std::array<Point, 3> p;
  bool edge_on = false;
  bool receiver_anywhere = false;  // a surface a shadowed receiver can lie on under `anywhere`
  // Plane depth = e * u + f * v + g; inward edge k: A[k] u + B[k] v + C[k] >= 0.
  double e = 0, f = 0, g = 0;
  std::array<double, 3> A{}, B{}, C{};
};

Triangle make_triangle(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c, MeshKind kind) {
  Triangle t;
  t.p = {Point{a.u, a.v, a.depth}, Point{b.u, b.v, b.depth}, Point{c.u, c.v, c.depth}};
  const double area2 = second_layer::projected_area2(a, b, c);
  t.receiver_anywhere = kind == MeshKind::open || area2 >= 0;
  t.edge_on = second_layer::edge_on(a, b, c);
  if (t.edge_on) return t;
  // Depth plane through the three vertices, solved by Cramer's rule on (u, v, 1).
  const double det = area2;
  t.e = ((b.depth - a.depth) * (c.v - a.v) - (c.depth - a.depth) * (b.v - a.v)) / det;
  t.f = ((c.depth - a.depth) * (b.u - a.u) - (b.depth - a.depth) * (c.u - a.u)) / det;
  t.g = a.depth - t.e * a.u - t.f * a.v;
  const double s = area2 > 0 ? 1.0 : -1.0;
  for (int k = 0; k < 3; ++k) {
    const Point& p = t.p[k];
    const Point& q = t.p[(k + 1) % 3];
    // s * cross(q - p, x - p) >= 0 inside.
    t.A[k] = -s * (q[1] - p[1]);
    t.B[k] = s * (q[0] - p[0]);
    t.C[k] = -(t.A[k] * p[0] + t.B[k] * p[1]);
  }
  return t;
}

struct Clipped {
  uint32_t triangle;
  double zmin, zmax;
  Poly poly;
};

}  // namespace

void apply_reference_caps(const LightSpaceScene& scene, TileCoord tile, ReceiverContract receivers,
                          double coplanar_epsilon, float exit_margin, TileIntervals& intervals,
                          ReferenceCapStats* stats) {
  const uint32_t size = intervals.size;
  const double u0 = double(tile.x) * size, v0 = double(tile.y) * size;
  const Scene& world = scene.scene();
  std::vector<Triangle> triangles;
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    triangles.push_back(make_triangle(scene.vertex(tri[0]), scene.vertex(tri[1]), scene.vertex(tri[2]),
                                      world.meshes[world.triangle_mesh[t]].kind));
  }
  // Patches over nearly closed meshes' holes bound their solids (anywhere only; no surface under `surfaces`).
  if (receivers == ReceiverContract::anywhere)
    for (uint32_t t : scene.patches_of(tile)) {
      const auto& tri = world.patch_triangles[t];
      triangles.push_back(
          make_triangle(scene.vertex(tri[0]), scene.vertex(tri[1]), scene.vertex(tri[2]), MeshKind::closed));
    }
  // Texel -> triangles whose box touches its square (CSR), for texels with an exit only.
  auto has_exit = [&](size_t i) {
    const DepthInterval& t = intervals.texels[i];
    return t.upper > t.lower && t.lower < 1.0f;
  };
  std::vector<uint32_t> offsets(size_t(size) * size + 1, 0);
  auto for_each_texel = [&](const Triangle& t, auto&& visit) {
    const double lo_u = std::min({t.p[0][0], t.p[1][0], t.p[2][0]}) - u0;
    const double hi_u = std::max({t.p[0][0], t.p[1][0], t.p[2][0]}) - u0;
    const double lo_v = std::min({t.p[0][1], t.p[1][1], t.p[2][1]}) - v0;
    const double hi_v = std::max({t.p[0][1], t.p[1][1], t.p[2][1]}) - v0;
    if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) return;
    const uint32_t i0 = uint32_t(std::max(0.0, std::floor(lo_u) - 1)), i1 = uint32_t(std::min(size - 1.0, std::floor(hi_u)));
    const uint32_t j0 = uint32_t(std::max(0.0, std::floor(lo_v) - 1)), j1 = uint32_t(std::min(size - 1.0, std::floor(hi_v)));
    for (uint32_t j = j0; j <= j1; ++j)
      for (uint32_t i = i0; i <= i1; ++i)
        if (has_exit(size_t(j) * size + i)) visit(size_t(j) * size + i);
  };
  for (const Triangle& t : triangles) for_each_texel(t, [&](size_t i) { ++offsets[i + 1]; });
  for (size_t k = 1; k < offsets.size(); ++k) offsets[k] += offsets[k - 1];
  std::vector<uint32_t> members(offsets.back());
  {
    std::vector<uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (uint32_t n = 0; n < triangles.size(); ++n)
      for_each_texel(triangles[n], [&](size_t i) { members[cursor[i]++] = n; });
  }

  ReferenceCapStats local;
  Poly scratch;
  std::vector<Clipped> clipped;
  for (uint32_t j = 0; j < size; ++j)
    for (uint32_t i = 0; i < size; ++i) {
      const size_t texel = size_t(j) * size + i;
      if (offsets[texel] == offsets[texel + 1]) continue;
      ++local.texels;
      DepthInterval& interval = intervals.texels[texel];
      const double su = u0 + i, sv = v0 + j;
      // Beyond this depth a cap no longer changes the interval (float(cap) - margin >= upper).
      const double enough = double(interval.upper) + double(exit_margin) + 1e-6;
      clipped.clear();
      for (uint32_t k = offsets[texel]; k < offsets[texel + 1]; ++k) {
        const Triangle& t = triangles[members[k]];
        if (receivers == ReceiverContract::anywhere && !t.receiver_anywhere) continue;
        Poly poly(t.p.begin(), t.p.end());
        cut(poly, scratch, 1, 0, 0, -su);
        cut(poly, scratch, -1, 0, 0, su + 1);
        cut(poly, scratch, 0, 1, 0, -sv);
        cut(poly, scratch, 0, -1, 0, sv + 1);
        ++local.clipped;
        if (poly.empty()) continue;
        double zmax = -std::numeric_limits<double>::infinity();
        for (const Point& p : poly) zmax = std::max(zmax, p[2]);
        clipped.push_back({members[k], shallowest(poly), zmax, std::move(poly)});
      }
      double cap = std::numeric_limits<double>::infinity();
      // Near cover counts below this depth only (second_layer::near_cover_offset).
      const double floor_depth = double(interval.lower) + second_layer::near_cover_offset(coplanar_epsilon);
      if (receivers == ReceiverContract::anywhere) {
        for (const Clipped& c : clipped) cap = std::min(cap, c.zmin);
      } else {
        std::sort(clipped.begin(), clipped.end(), [](const Clipped& a, const Clipped& b) { return a.zmin < b.zmin; });
        for (const Clipped& back : clipped) {
          if (back.zmin >= std::min(cap, enough)) break;  // nothing deeper can lower the cap
          const Triangle& tb = triangles[back.triangle];
          if (tb.edge_on) {
            cap = std::min(cap, back.zmin);
            continue;
          }
          for (const Clipped& front : clipped) {
            if (cap <= back.zmin) break;
            const Triangle& tf = triangles[front.triangle];
            if (front.triangle == back.triangle || tf.edge_on) continue;
            if (!(front.zmin + second_layer::kSameSurface < back.zmax)) continue;
            Poly covered = back.poly;
            for (int k = 0; k < 3 && !covered.empty(); ++k) cut(covered, scratch, tf.A[k], tf.B[k], 0, tf.C[k]);
            ++local.pair_clips;
            if (covered.empty()) continue;
            // Behind by epsilon: depth - (e u + f v + g) - epsilon >= 0, at any depth.
            Poly region = covered;
            cut(region, scratch, -tf.e, -tf.f, 1, -tf.g - coplanar_epsilon);
            if (!region.empty()) cap = std::min(cap, shallowest(region));
            // Behind by more than the same-surface gap, and deeper than the floor (near cover).
            cut(covered, scratch, -tf.e, -tf.f, 1, -tf.g - second_layer::kSameSurface);
            if (!covered.empty()) cut(covered, scratch, 0, 0, 1, -floor_depth);
            if (!covered.empty()) cap = std::min(cap, shallowest(covered));
          }
        }
      }
      if (std::isfinite(cap))
        interval.upper = std::max(interval.lower, std::min(interval.upper, float(cap) - exit_margin));
    }
  if (stats) {
    stats->texels += local.texels;
    stats->clipped += local.clipped;
    stats->pair_clips += local.pair_clips;
  }
}

}  // namespace shadowtiles
