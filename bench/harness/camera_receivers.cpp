#include "bench/harness/camera_receivers.hpp"

#include <cmath>

#include "builder/embree_world_scene.hpp"

namespace shadowtiles::bench {
namespace {

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 normalized(const Vec3& a) {
  double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  return l > 0 ? Vec3{a[0] / l, a[1] / l, a[2] / l} : Vec3{0, 0, 0};
}

}  // namespace

std::vector<Receiver> camera_receivers(const EmbreeDevice& device, const Scene& scene, UpAxis up,
                                       const CameraSpec& camera) {
  std::vector<Receiver> receivers;
  if (camera.width == 0 || camera.height == 0 || scene.triangles.empty()) return receivers;
  // The camera looks along the direction a sun at (azimuth, elevation) would shine.
  auto view = light_direction_from_sun(camera.azimuth, camera.elevation, up);
  if (!view) return receivers;
  const Vec3 centre = scene_centre(scene);
  Vec3 extent;
  for (int i = 0; i < 3; ++i) extent[i] = scene.bounds.max[i] - scene.bounds.min[i];
  const double radius = 0.5 * std::sqrt(extent[0] * extent[0] + extent[1] * extent[1] + extent[2] * extent[2]);
  const Vec3 forward = normalized(*view);
  // Camera-relative coordinates (origin at the scene centre) keep float precision in Embree.
  const Vec3 eye{-forward[0] * 1.3 * radius, -forward[1] * 1.3 * radius, -forward[2] * 1.3 * radius};
  const Vec3 world_up = up == UpAxis::z ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
  Vec3 right = normalized(cross(forward, world_up));
  if (right == Vec3{0, 0, 0}) right = {1, 0, 0};  // looking straight down
  const Vec3 cam_up = cross(right, forward);

  EmbreeScene rtc(rtcNewScene(device.get()));
  commit_world_triangles(device, rtc, scene, centre);

  const double tan_half = std::tan(camera.fov * M_PI / 360.0);
  const double aspect = double(camera.width) / double(camera.height);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  receivers.reserve(size_t(camera.width) * camera.height);
  for (uint32_t y = 0; y < camera.height; ++y) {
    for (uint32_t x = 0; x < camera.width; ++x) {
      const double sx = (2.0 * (x + 0.5) / camera.width - 1.0) * tan_half * aspect;
      const double sy = (1.0 - 2.0 * (y + 0.5) / camera.height) * tan_half;
      Vec3 dir = normalized({forward[0] + sx * right[0] + sy * cam_up[0], forward[1] + sx * right[1] + sy * cam_up[1],
                             forward[2] + sx * right[2] + sy * cam_up[2]});
      RTCRayHit hit = world_ray(eye, dir);
      rtcIntersect1(rtc.get(), &context, &hit);
      if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      const double t = hit.ray.tfar;
      Receiver r;
      for (int i = 0; i < 3; ++i) r.position[i] = centre[i] + eye[i] + t * dir[i];
      r.normal = normalized({hit.hit.Ng_x, hit.hit.Ng_y, hit.hit.Ng_z});
      r.triangle = hit.hit.primID;
      receivers.push_back(r);
    }
  }
  return receivers;
}

}  // namespace shadowtiles::bench
