#include "builder/ground_truth.hpp"

#include <cmath>
#include <limits>

namespace shadowtiles {

GroundTruth::GroundTruth(const EmbreeDevice& device, const Scene& scene, const Vec3& light_direction)
    : scene_(rtcNewScene(device.get())) {
  for (int i = 0; i < 3; ++i) centre_[i] = 0.5 * (scene.bounds.min[i] + scene.bounds.max[i]);
  double length = std::sqrt(light_direction[0] * light_direction[0] + light_direction[1] * light_direction[1] +
                            light_direction[2] * light_direction[2]);
  for (int i = 0; i < 3; ++i) to_sun_[i] = -light_direction[i] / length;
  double diagonal = 0;
  for (int i = 0; i < 3; ++i) diagonal += std::pow(scene.bounds.max[i] - scene.bounds.min[i], 2);
  epsilon_ = 1e-5 * std::sqrt(diagonal);

  rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
  if (!scene.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                 RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                                 scene.vertices.size()));
    for (size_t v = 0; v < scene.vertices.size(); ++v)
      for (int i = 0; i < 3; ++i) vertices[3 * v + i] = float(scene.vertices[v][i] - centre_[i]);
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                   RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
                                                                   scene.triangles.size()));
    for (size_t t = 0; t < scene.triangles.size(); ++t)
      for (int i = 0; i < 3; ++i) indices[3 * t + i] = scene.triangles[t][i];
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_.get(), geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(scene_.get());
}

bool GroundTruth::lit(const Vec3& world) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray{};
  ray.org_x = float(world[0] - centre_[0]);
  ray.org_y = float(world[1] - centre_[1]);
  ray.org_z = float(world[2] - centre_[2]);
  ray.dir_x = float(to_sun_[0]);
  ray.dir_y = float(to_sun_[1]);
  ray.dir_z = float(to_sun_[2]);
  ray.tnear = float(epsilon_);
  ray.tfar = std::numeric_limits<float>::infinity();
  ray.mask = 0xFFFFFFFFu;
  rtcOccluded1(scene_.get(), &context, &ray);
  return ray.tfar >= 0;  // Embree sets tfar to -inf when occluded
}

}  // namespace shadowtiles
