#include "builder/solid_interior.hpp"

#include <cmath>
#include <limits>

#include "builder/embree_world_scene.hpp"
#include "codec/vec3_math.hpp"

namespace shadowtiles {
namespace {

// The solid's surfaces as one Embree geometry, with +1 (faces the light: entering from the sun's
// side) or -1 per primitive.
struct SolidSurfaces {
  EmbreeScene scene;
  std::vector<int8_t> sign;
};

SolidSurfaces solid_surfaces(const EmbreeDevice& device, const Scene& scene, const Vec3& light,
                             const Vec3& centre) {
  SolidSurfaces out{EmbreeScene(rtcNewScene(device.get())), {}};
  std::vector<std::array<uint32_t, 3>> triangles;
  auto add = [&](const std::array<uint32_t, 3>& t) {
    const Vec3 n = cross(sub(scene.vertices[t[1]], scene.vertices[t[0]]), sub(scene.vertices[t[2]], scene.vertices[t[0]]));
    triangles.push_back(t);
    out.sign.push_back(dot(n, light) <= 0 ? 1 : -1);  // edge-on counts as facing, as the renderer does
  };
  for (size_t t = 0; t < scene.triangles.size(); ++t)
    if (scene.meshes[scene.triangle_mesh[t]].kind != MeshKind::open) add(scene.triangles[t]);
  for (const auto& t : scene.patch_triangles) add(t);
  rtcSetSceneFlags(out.scene.get(), RTC_SCENE_FLAG_ROBUST);
  if (!triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), scene.vertices.size()));
    for (size_t v = 0; v < scene.vertices.size(); ++v)
      for (int i = 0; i < 3; ++i) vertices[3 * v + i] = float(scene.vertices[v][i] - centre[i]);
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), triangles.size()));
    for (size_t t = 0; t < triangles.size(); ++t)
      for (int i = 0; i < 3; ++i) indices[3 * t + i] = triangles[t][i];
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(out.scene.get(), geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(out.scene.get());
  return out;
}

}  // namespace

std::vector<uint8_t> receivers_inside_solids(const EmbreeDevice& device, const Scene& scene,
                                             const Vec3& light_direction, std::span<const Receiver> receivers) {
  std::vector<uint8_t> inside(receivers.size(), 0);
  const double length = norm(light_direction);
  if (receivers.empty() || !(length > 0)) return inside;
  const Vec3 light{light_direction[0] / length, light_direction[1] / length, light_direction[2] / length};
  const Vec3 to_sun{-light[0], -light[1], -light[2]};
  const Vec3 centre = scene_centre(scene);
  const double diagonal = norm(sub(scene.bounds.max, scene.bounds.min));
  const double off_surface = 1e-5 * diagonal;  // GroundTruth's epsilon: off the receiver's own face
  const float step = float(1e-7 * diagonal);    // past a hit before looking for the next one
  SolidSurfaces solid = solid_surfaces(device, scene, light, centre);
  if (solid.sign.empty()) return inside;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t i = 0; i < receivers.size(); ++i) {
    const Receiver& r = receivers[i];
    const Vec3 origin{r.position[0] + off_surface * r.normal[0] - centre[0],
                      r.position[1] + off_surface * r.normal[1] - centre[1],
                      r.position[2] + off_surface * r.normal[2] - centre[2]};
    int counter = 0;
    float tnear = 0;
    // Every solid surface between the receiver and the sun, nearest first (bounded: a degenerate
    // stack of coplanar faces cannot loop for ever).
    for (size_t hits = 0; hits < solid.sign.size() + 1; ++hits) {
      RTCRayHit ray = world_ray(origin, to_sun);
      ray.ray.tnear = tnear;
      rtcIntersect1(solid.scene.get(), &context, &ray);
      if (ray.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
      counter += solid.sign[ray.hit.primID];
      tnear = ray.ray.tfar + step;
    }
    inside[i] = counter > 0;
  }
  return inside;
}

size_t drop_receivers_inside_solids(const EmbreeDevice& device, const Scene& scene, const Vec3& light_direction,
                                    std::vector<Receiver>& receivers) {
  const std::vector<uint8_t> inside = receivers_inside_solids(device, scene, light_direction, receivers);
  size_t kept = 0;
  for (size_t i = 0; i < receivers.size(); ++i)
    if (!inside[i]) receivers[kept++] = receivers[i];
  const size_t dropped = receivers.size() - kept;
  receivers.resize(kept);
  return dropped;
}

}  // namespace shadowtiles
