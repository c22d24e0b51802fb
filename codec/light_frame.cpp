#include "codec/light_frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "codec/vec3_math.hpp"

namespace shadowtiles {
namespace {

Vec3 scaled(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
bool finite(const Vec3& a) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }
bool is_power_of_two(uint32_t x) { return x != 0 && (x & (x - 1)) == 0; }

constexpr uint32_t kMaxResolution = 1u << 20;
// Padding as a fraction of the extent/depth range: keeps geometry off the map border and off the
// near plane, where rays start.
constexpr double kPadding = 1e-3;
// The fewest depth steps a quantising method uses (CPVS: max(map side, 8) steps over [0, 1]).
constexpr uint32_t kMinQuantisedSteps = 8;

struct Basis {
  Vec3 x, y, z;
};

Result<Basis> basis_for(const Vec3& direction) {
  double len = norm(direction);
  if (!finite(direction) || !(len > 1e-12))
    return make_error(ErrorCode::invalid_input, "light direction must be finite and non-zero");
  Vec3 z = scaled(direction, 1.0 / len);
  // Helper axis least aligned with z keeps the basis well conditioned for any direction.
  Vec3 helper = std::fabs(z[2]) < 0.9 ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
  Vec3 x = cross(helper, z);
  x = scaled(x, 1.0 / norm(x));
  Vec3 y = cross(z, x);  // right-handed: x cross y = z
  return Basis{x, y, z};
}

struct Footprint {
  double min_x, max_x, min_y, max_y, min_z, max_z;
};

Result<Footprint> project_bounds(const Basis& basis, const WorldBounds& bounds) {
  if (!finite(bounds.min) || !finite(bounds.max))
    return make_error(ErrorCode::invalid_input, "scene bounds are not finite");
  for (int i = 0; i < 3; ++i)
    if (bounds.min[i] > bounds.max[i]) return make_error(ErrorCode::invalid_input, "scene bounds are empty");
  Footprint f{std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
              std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
              std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()};
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 p{(corner & 1) ? bounds.max[0] : bounds.min[0], (corner & 2) ? bounds.max[1] : bounds.min[1],
           (corner & 4) ? bounds.max[2] : bounds.min[2]};
    double x = dot(p, basis.x), y = dot(p, basis.y), z = dot(p, basis.z);
    f.min_x = std::min(f.min_x, x); f.max_x = std::max(f.max_x, x);
    f.min_y = std::min(f.min_y, y); f.max_y = std::max(f.max_y, y);
    f.min_z = std::min(f.min_z, z); f.max_z = std::max(f.max_z, z);
  }
  return f;
}

// A degenerate scene (one point, a plane seen edge-on) still needs a positive size.
double minimum_size(double scale) { return std::max(scale, 1.0) * 1e-6; }
double padded_size(double size, double scale) {
  return std::max(size, minimum_size(scale)) * (1.0 + 2.0 * kPadding);
}

}  // namespace

Result<Vec3> light_direction_from_sun(double azimuth_deg, double elevation_deg, UpAxis up) {
  if (!std::isfinite(azimuth_deg) || !std::isfinite(elevation_deg))
    return make_error(ErrorCode::invalid_input, "sun azimuth and elevation must be finite");
  if (elevation_deg <= 0.0 || elevation_deg > 90.0)
    return make_error(ErrorCode::invalid_input,
                      "sun elevation must be in (0, 90] degrees, got " + std::to_string(elevation_deg));
  const double deg = M_PI / 180.0;
  double az = azimuth_deg * deg, el = elevation_deg * deg;
  double east = std::sin(az) * std::cos(el), north = std::cos(az) * std::cos(el), upward = std::sin(el);
  // Toward the sun; the light travels the other way.
  Vec3 to_sun = up == UpAxis::z ? Vec3{east, north, upward} : Vec3{east, upward, -north};
  return scaled(to_sun, -1.0);
}

Result<LightFrame> LightFrame::fit(const Vec3& light_direction, const WorldBounds& bounds, uint32_t resolution,
                                   double far_margin_texels) {
  if (!is_power_of_two(resolution) || resolution > kMaxResolution)
    return make_error(ErrorCode::invalid_input,
                      "resolution must be a power of two in [1, 2^20], got " + std::to_string(resolution));
  if (!std::isfinite(far_margin_texels) || far_margin_texels < 0)
    return make_error(ErrorCode::invalid_input, "far margin must be finite and >= 0");
  auto basis = basis_for(light_direction);
  if (!basis) return basis.error();
  auto footprint = project_bounds(*basis, bounds);
  if (!footprint) return footprint.error();
  const Footprint& f = *footprint;
  double scale = std::max({std::fabs(f.min_x), std::fabs(f.max_x), std::fabs(f.min_y), std::fabs(f.max_y),
                           std::fabs(f.min_z), std::fabs(f.max_z)});
  double extent = padded_size(std::max(f.max_x - f.min_x, f.max_y - f.min_y), scale);
  // Depth: near padding, the bounds, then the far margin. The far part is sized so that, with the
  // final range, it holds the relative padding, the margin in texels and two quantisation steps.
  double depth_size = std::max(f.max_z - f.min_z, minimum_size(scale));
  double near_padding = kPadding * depth_size;
  double far_margin = kPadding * depth_size + far_margin_texels * extent / resolution;
  double step_fraction = 2.0 / std::max(resolution, kMinQuantisedSteps);
  double depth_range = (near_padding + depth_size + far_margin) / (1.0 - step_fraction);
  double cx = 0.5 * (f.min_x + f.max_x), cy = 0.5 * (f.min_y + f.max_y);
  double x0 = cx - 0.5 * extent, y0 = cy - 0.5 * extent, z0 = f.min_z - near_padding;
  Vec3 origin{x0 * basis->x[0] + y0 * basis->y[0] + z0 * basis->z[0],
              x0 * basis->x[1] + y0 * basis->y[1] + z0 * basis->z[1],
              x0 * basis->x[2] + y0 * basis->y[2] + z0 * basis->z[2]};
  return from_parameters(basis->z, origin, extent, depth_range, resolution);
}

Result<LightFrame> LightFrame::from_parameters(const Vec3& light_direction, const Vec3& origin, double extent,
                                               double depth_range, uint32_t resolution) {
  if (!is_power_of_two(resolution) || resolution > kMaxResolution)
    return make_error(ErrorCode::invalid_input,
                      "resolution must be a power of two in [1, 2^20], got " + std::to_string(resolution));
  if (!finite(origin) || !std::isfinite(extent) || !(extent > 0) || !std::isfinite(depth_range) ||
      !(depth_range > 0))
    return make_error(ErrorCode::invalid_input, "light frame origin, extent and depth range must be finite and positive");
  auto basis = basis_for(light_direction);
  if (!basis) return basis.error();
  LightFrame frame;
  frame.axis_x_ = basis->x;
  frame.axis_y_ = basis->y;
  frame.axis_z_ = basis->z;
  frame.origin_ = origin;
  frame.extent_ = extent;
  frame.depth_range_ = depth_range;
  frame.resolution_ = resolution;
  frame.texels_per_unit_ = resolution / extent;
  return frame;
}

Result<uint32_t> LightFrame::resolution_for_texel_size(const Vec3& light_direction, const WorldBounds& bounds,
                                                       double texel_size) {
  if (!std::isfinite(texel_size) || !(texel_size > 0))
    return make_error(ErrorCode::invalid_input, "texel size must be positive");
  auto frame = fit(light_direction, bounds, 1);
  if (!frame) return frame.error();
  uint32_t resolution = 1;
  while (frame->extent() / resolution > texel_size) {
    if (resolution == kMaxResolution)
      return make_error(ErrorCode::invalid_input,
                        "texel size " + std::to_string(texel_size) + " needs more than 2^20 texels per side (extent " +
                            std::to_string(frame->extent()) + ")");
    resolution *= 2;
  }
  return resolution;
}

Vec3 LightFrame::to_world(const LightSpacePoint& light) const {
  double units_per_texel = extent_ / resolution_;
  double x = light.u * units_per_texel, y = light.v * units_per_texel, z = light.depth * depth_range_;
  return {origin_[0] + x * axis_x_[0] + y * axis_y_[0] + z * axis_z_[0],
          origin_[1] + x * axis_x_[1] + y * axis_y_[1] + z * axis_z_[1],
          origin_[2] + x * axis_x_[2] + y * axis_y_[2] + z * axis_z_[2]};
}

}  // namespace shadowtiles
