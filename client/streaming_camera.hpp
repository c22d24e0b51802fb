// CameraView: a pinhole camera in world space, shared by the streaming client (prefetch of the tiles
// under a frustum) and the frame renderer (builder/frame_renderer.hpp, `shadowtiles render`).
// Pixel (x, y), row 0 at the top, looks along forward + sx * right + sy * up with
// sx = (2 (x + 0.5) / width - 1) tan(fov / 2) aspect and sy = (1 - 2 (y + 0.5) / height) tan(fov / 2).
// Thread safety: plain value types.
#pragma once

#include <array>
#include <cstdint>

#include "codec/light_frame.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct CameraView {
  Vec3 eye{0, 0, 1};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 0, 1};
  double vertical_fov_deg = 50;
  uint32_t width = 1280;
  uint32_t height = 720;
};

// Orthonormal camera basis and the per-pixel direction.
struct CameraBasis {
  Vec3 forward{}, right{}, up{};
  double tan_half_fov = 0;
  double aspect = 1;
  // Errors: invalid_input for a zero or non-finite view direction, an up parallel to it, a zero
  // frame size or a field of view outside (0, 180).
  static Result<CameraBasis> of(const CameraView& view);
  Vec3 pixel_direction(double x, double y, uint32_t width, uint32_t height) const;  // unit length
};

// A view of the whole `bounds` from `up`'s side: the eye on a sphere 1.3 bounding radii from the
// centre at azimuth 200 degrees (clockwise from north, as the sun) and 35 degrees elevation.
CameraView default_camera(const WorldBounds& bounds, UpAxis up, uint32_t width, uint32_t height);

}  // namespace shadowtiles
