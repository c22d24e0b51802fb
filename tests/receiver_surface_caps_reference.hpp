// Shared by the receiver-surface caps tests: the original per-texel clipping (the reference the fast
// caps must equal bit for bit) and a whole-scene comparison.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "builder/light_space_scene.hpp"
#include "builder/receiver_surface_caps.hpp"
#include "builder/scene_loader.hpp"
#include "testing_support.hpp"

namespace shadowtiles::testing {

// ---- Reference: the original implementation (builder/dual_depth_renderer.cpp before issue #8). ----
struct ReferenceClipVertex {
  double u, v, depth;
};

inline void reference_clip(std::vector<ReferenceClipVertex>& polygon, std::vector<ReferenceClipVertex>& scratch,
                           bool along_u, double bound, double sign) {
  scratch.clear();
  const size_t n = polygon.size();
  for (size_t k = 0; k < n; ++k) {
    const ReferenceClipVertex& p = polygon[k];
    const ReferenceClipVertex& q = polygon[(k + 1) % n];
    const double dp = sign * ((along_u ? p.u : p.v) - bound), dq = sign * ((along_u ? q.u : q.v) - bound);
    if (dp >= 0) scratch.push_back(p);
    if ((dp >= 0) != (dq >= 0)) {
      const double t = dp / (dp - dq);
      scratch.push_back({p.u + t * (q.u - p.u), p.v + t * (q.v - p.v), p.depth + t * (q.depth - p.depth)});
    }
  }
  polygon.swap(scratch);
}

inline void reference_lower_caps(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                                 const TexelWindow& window, std::vector<float>& cap) {
  const uint32_t size = window.size;
  const double u0 = window.u0, v0 = window.v0;
  std::vector<ReferenceClipVertex> polygon, scratch;
  const double lo_u = std::min({a.u, b.u, c.u}) - u0, hi_u = std::max({a.u, b.u, c.u}) - u0;
  const double lo_v = std::min({a.v, b.v, c.v}) - v0, hi_v = std::max({a.v, b.v, c.v}) - v0;
  // Closed squares (issue #14): a box starting exactly on a texel border also touches the texel before it.
  if (hi_u < 0 || hi_v < 0 || lo_u > size || lo_v > size) return;
  const uint32_t i0 = uint32_t(std::max(0.0, std::floor(lo_u) - 1)), i1 = uint32_t(std::min(size - 1.0, std::floor(hi_u)));
  const uint32_t j0 = uint32_t(std::max(0.0, std::floor(lo_v) - 1)), j1 = uint32_t(std::min(size - 1.0, std::floor(hi_v)));
  for (uint32_t j = j0; j <= j1; ++j)
    for (uint32_t i = i0; i <= i1; ++i) {
      const double su = u0 + i, sv = v0 + j;
      polygon = {{a.u, a.v, a.depth}, {b.u, b.v, b.depth}, {c.u, c.v, c.depth}};
      reference_clip(polygon, scratch, true, su, 1);
      if (!polygon.empty()) reference_clip(polygon, scratch, true, su + 1, -1);
      if (!polygon.empty()) reference_clip(polygon, scratch, false, sv, 1);
      if (!polygon.empty()) reference_clip(polygon, scratch, false, sv + 1, -1);
      if (polygon.empty()) continue;
      double shallowest = polygon.front().depth;
      for (const ReferenceClipVertex& p : polygon) shallowest = std::min(shallowest, p.depth);
      float& slot = cap[size_t(j) * size + i];
      slot = std::min(slot, float(shallowest));
    }
}

inline std::vector<float> reference_receiver_surface_caps(const LightSpaceScene& scene, TileCoord tile) {
  const uint32_t size = scene.layout().tile_size();
  const TexelWindow window{double(tile.x) * size, double(tile.y) * size, size};
  std::vector<float> cap(size_t(size) * size, std::numeric_limits<float>::infinity());
  const Scene& world = scene.scene();
  for (uint32_t t : scene.triangles_of(tile)) {
    const auto& tri = world.triangles[t];
    const LightSpacePoint& a = scene.vertex(tri[0]);
    const LightSpacePoint& b = scene.vertex(tri[1]);
    const LightSpacePoint& c = scene.vertex(tri[2]);
    const MeshKind kind = world.meshes[world.triangle_mesh[t]].kind;
    const double nz = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
    if (kind != MeshKind::open && nz < 0) continue;
    reference_lower_caps(a, b, c, window, cap);
  }
  return cap;
}
// ---- End of reference. ----

// Texels whose caps differ in any bit (so -0 vs +0 or a last-ulp difference count).
inline size_t differing_texels(const std::vector<float>& x, const std::vector<float>& y) {
  size_t differing = 0;
  for (size_t i = 0; i < x.size(); ++i) differing += std::bit_cast<uint32_t>(x[i]) != std::bit_cast<uint32_t>(y[i]);
  return differing;
}

// Every texel of every tile of a real scene, built as `shadowtiles build` frames it.
inline void expect_scene_identical(const std::string& file, UpAxis up, std::vector<std::string> heightfields,
                                   double azimuth, double elevation, uint32_t resolution, uint32_t tile_size) {
  LoadOptions load;
  load.up = up;
  load.heightfield_meshes = std::move(heightfields);
  auto scene = load_scene(shared_scene(file), load);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  auto direction = light_direction_from_sun(azimuth, elevation, up);
  ASSERT_TRUE(direction.ok());
  auto frame = LightFrame::fit(*direction, scene->bounds, resolution);
  ASSERT_TRUE(frame.ok());
  auto layout = TileLayout::make(resolution, tile_size);
  ASSERT_TRUE(layout.ok());
  LightSpaceScene light_scene(*scene, *frame, *layout);
  ReceiverCapCounts counts;
  size_t differing = 0, capped = 0;
  for (uint32_t y = 0; y < layout->tiles_per_side(); ++y)
    for (uint32_t x = 0; x < layout->tiles_per_side(); ++x) {
      const std::vector<float> fast = receiver_surface_caps(light_scene, {x, y}, &counts);
      const std::vector<float> reference = reference_receiver_surface_caps(light_scene, {x, y});
      differing += differing_texels(fast, reference);
      capped += size_t(std::count_if(reference.begin(), reference.end(), [](float f) { return !std::isinf(f); }));
    }
  EXPECT_EQ(differing, 0u) << file;
  EXPECT_GT(capped, size_t(resolution) * resolution / 50) << file << ": the scene must cap a part of the map";
  EXPECT_GT(counts.interior, 0u) << file;
  std::printf("%s: capped texels %zu, clipped %llu, interior %llu, fallback %llu\n", file.c_str(), capped,
              (unsigned long long)counts.clipped, (unsigned long long)counts.interior,
              (unsigned long long)counts.fallback);
}

}  // namespace shadowtiles::testing
