// LightFrame: the orthographic light space of a directional light (docs/architecture.md §3).
//
// World point p maps to continuous texel coordinates (u, v) over an R x R map and a normalised depth
// d in [0, 1] along the light direction; texel (i, j) covers u in [i, i+1), v in [j, j+1) and its ray
// starts at the texel centre. Computed in double so huge world coordinates (10^6 units) keep their
// precision; the builder hands Embree tile-local coordinates only.
// The basis is right-handed (x cross y = z, z = light travel direction), so a triangle's facing is
// preserved by the world -> light transform.
// Thread safety: immutable value type.
#pragma once

#include <array>
#include <cstdint>

#include "common/result.hpp"

namespace shadowtiles {

using Vec3 = std::array<double, 3>;

struct LightSpacePoint {
  double u = 0;      // texel units, [0, R) inside the map
  double v = 0;
  double depth = 0;  // normalised, 0 = near plane, 1 = far plane
};

struct WorldBounds {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
};

enum class UpAxis { z, y };

// Direction the light travels (from the sun toward the scene) for a sun at azimuth `azimuth_deg`
// (clockwise from north) and elevation `elevation_deg` above the horizon. North is +Y for z-up
// scenes and -Z for y-up scenes; east is +X in both.
Result<Vec3> light_direction_from_sun(double azimuth_deg, double elevation_deg, UpAxis up);

class LightFrame {
 public:
  // Default room between the deepest geometry and the far plane, in texel widths: comfortably more
  // than the default query bias (2) and exit margin (4).
  static constexpr double kDefaultFarMarginTexels = 16;

  // Fits the frame to `bounds`: square extent covering the bounds' projection, depth range covering
  // the bounds, both padded slightly so geometry never sits exactly on the border. Beyond the deepest
  // geometry the depth range adds `far_margin_texels` texel widths plus two steps of a depth quantised
  // to max(resolution, 8) steps (CPVS), so no surface reaches depth 1: a receiver beyond the far
  // plane can then be answered as if on it (nothing shadows it but what shadows the far plane).
  // Errors: zero or non-finite direction, non-finite or inverted bounds, resolution not a power of
  // two in [1, 2^20], a negative or non-finite margin.
  static Result<LightFrame> fit(const Vec3& light_direction, const WorldBounds& bounds, uint32_t resolution,
                                double far_margin_texels = kDefaultFarMarginTexels);
  // Rebuilds a frame from stored parameters (see members); validates them like fit().
  static Result<LightFrame> from_parameters(const Vec3& light_direction, const Vec3& origin, double extent,
                                            double depth_range, uint32_t resolution);

  // Smallest power-of-two resolution whose texel is no larger than `texel_size` world units for a
  // frame fitted to `bounds` (clamped to 2^20: the error says so when it does not reach).
  static Result<uint32_t> resolution_for_texel_size(const Vec3& light_direction, const WorldBounds& bounds,
                                                    double texel_size);

  // Inline: the batch query's transform pass calls it per point (1M-point batches).
  LightSpacePoint to_light(const Vec3& world) const {
    const double x = world[0] - origin_[0], y = world[1] - origin_[1], z = world[2] - origin_[2];
    return {(x * axis_x_[0] + y * axis_x_[1] + z * axis_x_[2]) * texels_per_unit_,
            (x * axis_y_[0] + y * axis_y_[1] + z * axis_y_[2]) * texels_per_unit_,
            (x * axis_z_[0] + y * axis_z_[1] + z * axis_z_[2]) / depth_range_};
  }
  Vec3 to_world(const LightSpacePoint& light) const;

  const Vec3& direction() const { return axis_z_; }  // unit, light travel direction
  const Vec3& axis_x() const { return axis_x_; }
  const Vec3& axis_y() const { return axis_y_; }
  const Vec3& origin() const { return origin_; }      // world point at u = 0, v = 0, depth = 0
  double extent() const { return extent_; }           // world size of the map side
  double depth_range() const { return depth_range_; } // world distance from depth 0 to depth 1
  uint32_t resolution() const { return resolution_; }
  double texel_size() const { return extent_ / resolution_; }
  // World distance -> normalised depth difference.
  double depth_from_world(double distance) const { return distance / depth_range_; }

 private:
  Vec3 axis_x_{}, axis_y_{}, axis_z_{};
  Vec3 origin_{};
  double extent_ = 0;
  double depth_range_ = 0;
  uint32_t resolution_ = 0;
  double texels_per_unit_ = 0;  // resolution_ / extent_, the value to_light() computed per call
};

}  // namespace shadowtiles
