// LightSpaceScene: the scene's vertices in light space (u, v in texels, depth normalised) and, per
// tile, the triangles whose light-space footprint overlaps it (a CSR index). Each tile's Embree BVH
// is then built from its own triangles only, so memory is bounded by one tile's working set per
// thread plus the scene, and tiles no triangle touches are known empty without casting a ray.
// Thread safety: immutable after construction; concurrent reads are safe.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "builder/scene.hpp"
#include "codec/light_frame.hpp"
#include "codec/tile_layout.hpp"

namespace shadowtiles {

class LightSpaceScene {
 public:
  LightSpaceScene(const Scene& scene, const LightFrame& frame, const TileLayout& layout);

  const Scene& scene() const { return scene_; }
  const LightFrame& frame() const { return frame_; }
  const TileLayout& layout() const { return layout_; }
  // Light-space position of a scene vertex (double: tile-local floats are derived from it).
  const LightSpacePoint& vertex(uint32_t index) const { return light_vertices_[index]; }
  // Triangles (indices into scene().triangles) that may cover a texel centre of `tile`.
  std::span<const uint32_t> triangles_of(TileCoord tile) const;
  // Patch triangles (indices into scene().patch_triangles) that may cover a texel centre of `tile`.
  std::span<const uint32_t> patches_of(TileCoord tile) const;
  uint64_t nonempty_tile_count() const { return nonempty_tiles_; }
  uint64_t triangle_references() const { return tile_triangles_.size(); }

 private:
  const Scene& scene_;
  LightFrame frame_;
  TileLayout layout_;
  std::vector<LightSpacePoint> light_vertices_;
  std::vector<uint64_t> tile_offsets_;   // tile_count + 1, row-major tiles
  std::vector<uint32_t> tile_triangles_;
  std::vector<uint64_t> patch_offsets_;  // the same for the patch triangles
  std::vector<uint32_t> tile_patches_;
  uint64_t nonempty_tiles_ = 0;
};

}  // namespace shadowtiles
