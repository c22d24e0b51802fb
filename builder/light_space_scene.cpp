#include "builder/light_space_scene.hpp"

#include <algorithm>
#include <cmath>

namespace shadowtiles {
namespace {

struct TileRange {
  uint32_t x0, x1, y0, y1;  // inclusive
  bool empty;
};

// Tiles whose texel centres a triangle's footprint may cover. Widened by half a texel so rounding in
// the double -> float move never loses a covered centre.
TileRange tile_range(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                     const TileLayout& layout) {
  double min_u = std::min({a.u, b.u, c.u}) - 0.5, max_u = std::max({a.u, b.u, c.u}) + 0.5;
  double min_v = std::min({a.v, b.v, c.v}) - 0.5, max_v = std::max({a.v, b.v, c.v}) + 0.5;
  double resolution = layout.resolution();
  if (max_u < 0 || max_v < 0 || min_u >= resolution || min_v >= resolution) return {0, 0, 0, 0, true};
  double tile = layout.tile_size();
  auto clamp_tile = [&](double texel) {
    double t = std::floor(std::clamp(texel, 0.0, resolution - 1) / tile);
    return uint32_t(t);
  };
  return {clamp_tile(min_u), clamp_tile(max_u), clamp_tile(min_v), clamp_tile(max_v), false};
}

}  // namespace

LightSpaceScene::LightSpaceScene(const Scene& scene, const LightFrame& frame, const TileLayout& layout)
    : scene_(scene), frame_(frame), layout_(layout) {
  light_vertices_.reserve(scene.vertices.size());
  for (const Vec3& p : scene.vertices) light_vertices_.push_back(frame.to_light(p));

  const uint32_t side = layout.tiles_per_side();
  // Two passes (count, then fill) build a CSR index without per-tile vectors.
  auto index = [&](const std::vector<std::array<uint32_t, 3>>& triangles, std::vector<uint64_t>& offsets,
                   std::vector<uint32_t>& references) {
    auto for_each_reference = [&](auto&& visit) {
      for (uint32_t t = 0; t < triangles.size(); ++t) {
        const auto& tri = triangles[t];
        TileRange r = tile_range(light_vertices_[tri[0]], light_vertices_[tri[1]], light_vertices_[tri[2]], layout);
        if (r.empty) continue;
        for (uint32_t y = r.y0; y <= r.y1; ++y)
          for (uint32_t x = r.x0; x <= r.x1; ++x) visit(uint64_t(y) * side + x, t);
      }
    };
    offsets.assign(layout.tile_count() + 1, 0);
    for_each_reference([&](uint64_t tile, uint32_t) { ++offsets[tile + 1]; });
    for (uint64_t i = 0; i < layout.tile_count(); ++i) offsets[i + 1] += offsets[i];
    references.resize(offsets.back());
    std::vector<uint64_t> cursor(offsets.begin(), offsets.end() - 1);
    for_each_reference([&](uint64_t tile, uint32_t t) { references[cursor[tile]++] = t; });
  };
  index(scene.triangles, tile_offsets_, tile_triangles_);
  for (uint64_t i = 0; i < layout.tile_count(); ++i)
    if (tile_offsets_[i + 1] != tile_offsets_[i]) ++nonempty_tiles_;
  index(scene.patch_triangles, patch_offsets_, tile_patches_);
}

std::span<const uint32_t> LightSpaceScene::triangles_of(TileCoord tile) const {
  uint64_t index = uint64_t(tile.y) * layout_.tiles_per_side() + tile.x;
  return {tile_triangles_.data() + tile_offsets_[index], tile_triangles_.data() + tile_offsets_[index + 1]};
}

std::span<const uint32_t> LightSpaceScene::patches_of(TileCoord tile) const {
  uint64_t index = uint64_t(tile.y) * layout_.tiles_per_side() + tile.x;
  return {tile_patches_.data() + patch_offsets_[index], tile_patches_.data() + patch_offsets_[index + 1]};
}

}  // namespace shadowtiles
