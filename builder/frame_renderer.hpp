// FrameRenderer: primary rays of a pinhole camera (client/streaming_camera.hpp) through a scene with
// Embree, one per pixel centre: what each pixel sees (world position and a normal facing the
// camera), the input of `shadowtiles render` (shading: builder/frame_shading.hpp).
// The BVH holds the scene relative to its bounds' centre (as GroundTruth does), so float precision
// follows the scene's size, not its distance from the world origin; positions come back in double.
// Errors: trace → invalid_input for a bad camera (CameraBasis::of).
// Thread safety: trace() may be called concurrently after construction; it runs `threads` workers.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/embree_device.hpp"
#include "builder/scene.hpp"
#include "client/streaming_camera.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct PrimaryHit {
  bool hit = false;
  Vec3 position{};  // world
  Vec3 normal{};    // unit geometric normal, turned toward the camera (open meshes show both sides)
};

struct FrameHits {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<PrimaryHit> pixels;  // row by row, row 0 at the top
  uint64_t hit_count() const;
};

class FrameRenderer {
 public:
  FrameRenderer(const EmbreeDevice& device, const Scene& scene);
  Result<FrameHits> trace(const CameraView& camera, unsigned threads = 2) const;

 private:
  EmbreeScene scene_;
  Vec3 centre_{};
};

}  // namespace shadowtiles
