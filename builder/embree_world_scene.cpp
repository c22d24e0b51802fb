#include "builder/embree_world_scene.hpp"

namespace shadowtiles {

Vec3 scene_centre(const Scene& scene) {
  Vec3 centre{};
  for (int i = 0; i < 3; ++i) centre[i] = 0.5 * (scene.bounds.min[i] + scene.bounds.max[i]);
  return centre;
}

void commit_world_triangles(const EmbreeDevice& device, const EmbreeScene& target, const Scene& scene,
                            const Vec3& centre) {
  rtcSetSceneFlags(target.get(), RTC_SCENE_FLAG_ROBUST);
  if (!scene.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                 RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                                 scene.vertices.size()));
    for (size_t v = 0; v < scene.vertices.size(); ++v)
      for (int i = 0; i < 3; ++i) vertices[3 * v + i] = float(scene.vertices[v][i] - centre[i]);
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                   RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
                                                                   scene.triangles.size()));
    for (size_t t = 0; t < scene.triangles.size(); ++t)
      for (int i = 0; i < 3; ++i) indices[3 * t + i] = scene.triangles[t][i];
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(target.get(), geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(target.get());
}

}  // namespace shadowtiles
