#include "client/streaming_camera.hpp"

#include <cmath>

namespace shadowtiles {
namespace {

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double length(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }
Vec3 scaled(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

}  // namespace

Result<CameraBasis> CameraBasis::of(const CameraView& view) {
  if (view.width == 0 || view.height == 0) return make_error(ErrorCode::invalid_input, "frame size must be > 0");
  if (!(view.vertical_fov_deg > 0 && view.vertical_fov_deg < 180))
    return make_error(ErrorCode::invalid_input, "field of view must be in (0, 180) degrees");
  Vec3 forward{view.target[0] - view.eye[0], view.target[1] - view.eye[1], view.target[2] - view.eye[2]};
  const double distance = length(forward);
  if (!(distance > 0) || !std::isfinite(distance))
    return make_error(ErrorCode::invalid_input, "camera eye and look-at target must differ and be finite");
  CameraBasis basis;
  basis.forward = scaled(forward, 1 / distance);
  Vec3 right = cross(basis.forward, view.up);
  const double right_length = length(right);
  if (!(right_length > 1e-9 * length(view.up)) || !std::isfinite(right_length))
    return make_error(ErrorCode::invalid_input, "camera up direction must not be parallel to the view direction");
  basis.right = scaled(right, 1 / right_length);
  basis.up = cross(basis.right, basis.forward);
  basis.tan_half_fov = std::tan(view.vertical_fov_deg * M_PI / 360.0);
  basis.aspect = double(view.width) / double(view.height);
  return basis;
}

Vec3 CameraBasis::pixel_direction(double x, double y, uint32_t width, uint32_t height) const {
  const double sx = (2.0 * (x + 0.5) / width - 1.0) * tan_half_fov * aspect;
  const double sy = (1.0 - 2.0 * (y + 0.5) / height) * tan_half_fov;
  Vec3 d{forward[0] + sx * right[0] + sy * up[0], forward[1] + sx * right[1] + sy * up[1],
         forward[2] + sx * right[2] + sy * up[2]};
  return scaled(d, 1 / length(d));
}

CameraView default_camera(const WorldBounds& bounds, UpAxis up, uint32_t width, uint32_t height) {
  CameraView view;
  view.width = width;
  view.height = height;
  Vec3 centre, extent;
  for (int i = 0; i < 3; ++i) {
    centre[i] = 0.5 * (bounds.min[i] + bounds.max[i]);
    extent[i] = bounds.max[i] - bounds.min[i];
  }
  const double radius = std::max(0.5 * length(extent), 1e-9);
  // Direction from the centre toward the eye: a "sun" at azimuth 200, elevation 35, seen from the
  // scene (the sun convention gives north and east for both up axes).
  auto toward_scene = light_direction_from_sun(200, 35, up);
  Vec3 to_eye = toward_scene ? scaled(*toward_scene, -1) : Vec3{0, -1, 1};
  // The bounding sphere just inside the vertical field of view would leave most scenes small (the
  // sphere is loose around flat sites and boxes): 0.6 of that distance frames them, 1.3 radii at least.
  const double fit = radius / std::sin(0.5 * view.vertical_fov_deg * M_PI / 180.0);
  const double distance = std::max(1.3 * radius, 0.6 * fit);
  view.target = centre;
  view.eye = {centre[0] + to_eye[0] * distance, centre[1] + to_eye[1] * distance, centre[2] + to_eye[2] * distance};
  view.up = up == UpAxis::z ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
  return view;
}

}  // namespace shadowtiles
