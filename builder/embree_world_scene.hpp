// The whole scene as one Embree triangle geometry, for rays traced in world space (ground truth,
// camera frames). Vertices are stored relative to `centre` (float precision stays at the scene's
// own scale however far it lies from the origin); callers offset ray origins the same way.
// Thread safety: call before the scene is traced; the committed scene may then be traced concurrently.
#pragma once

#include <limits>

#include "builder/embree_device.hpp"
#include "builder/scene.hpp"

namespace shadowtiles {

// The centre of the scene's bounds: the origin of the Embree coordinates.
Vec3 scene_centre(const Scene& scene);
// Adds every triangle of `scene` (robust traversal) and commits `target`.
void commit_world_triangles(const EmbreeDevice& device, const EmbreeScene& target, const Scene& scene,
                            const Vec3& centre);
// A ray for rtcIntersect1 from `origin` (Embree coordinates) along `direction`, unbounded, no hit yet.
inline RTCRayHit world_ray(const Vec3& origin, const Vec3& direction) {
  RTCRayHit ray{};
  ray.ray.org_x = float(origin[0]);
  ray.ray.org_y = float(origin[1]);
  ray.ray.org_z = float(origin[2]);
  ray.ray.dir_x = float(direction[0]);
  ray.ray.dir_y = float(direction[1]);
  ray.ray.dir_z = float(direction[2]);
  ray.ray.tnear = 0;
  ray.ray.tfar = std::numeric_limits<float>::infinity();
  ray.ray.mask = 0xFFFFFFFFu;
  ray.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  return ray;
}

}  // namespace shadowtiles
