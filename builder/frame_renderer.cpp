#include "builder/frame_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

namespace shadowtiles {

uint64_t FrameHits::hit_count() const {
  return uint64_t(std::count_if(pixels.begin(), pixels.end(), [](const PrimaryHit& p) { return p.hit; }));
}

FrameRenderer::FrameRenderer(const EmbreeDevice& device, const Scene& scene) : scene_(rtcNewScene(device.get())) {
  for (int i = 0; i < 3; ++i) centre_[i] = 0.5 * (scene.bounds.min[i] + scene.bounds.max[i]);
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

Result<FrameHits> FrameRenderer::trace(const CameraView& camera, unsigned threads) const {
  auto basis = CameraBasis::of(camera);
  if (!basis) return basis.error();
  for (double c : camera.eye)
    if (!std::isfinite(c)) return make_error(ErrorCode::invalid_input, "camera eye must be finite");
  FrameHits frame;
  frame.width = camera.width;
  frame.height = camera.height;
  frame.pixels.resize(size_t(camera.width) * camera.height);
  const Vec3 eye{camera.eye[0] - centre_[0], camera.eye[1] - centre_[1], camera.eye[2] - centre_[2]};
  auto trace_rows = [&](uint32_t first_row, uint32_t step) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (uint32_t y = first_row; y < camera.height; y += step) {
      for (uint32_t x = 0; x < camera.width; ++x) {
        const Vec3 dir = basis->pixel_direction(x, y, camera.width, camera.height);
        RTCRayHit ray{};
        ray.ray.org_x = float(eye[0]);
        ray.ray.org_y = float(eye[1]);
        ray.ray.org_z = float(eye[2]);
        ray.ray.dir_x = float(dir[0]);
        ray.ray.dir_y = float(dir[1]);
        ray.ray.dir_z = float(dir[2]);
        ray.ray.tnear = 0;
        ray.ray.tfar = std::numeric_limits<float>::infinity();
        ray.ray.mask = 0xFFFFFFFFu;
        ray.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_.get(), &context, &ray);
        if (ray.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        PrimaryHit& pixel = frame.pixels[size_t(y) * camera.width + x];
        pixel.hit = true;
        const double t = ray.ray.tfar;
        for (int i = 0; i < 3; ++i) pixel.position[i] = centre_[i] + eye[i] + t * dir[i];
        Vec3 n{ray.hit.Ng_x, ray.hit.Ng_y, ray.hit.Ng_z};
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const double facing = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
        const double scale = length > 0 ? (facing > 0 ? -1 : 1) / length : 0;
        for (int i = 0; i < 3; ++i) pixel.normal[i] = n[i] * scale;
      }
    }
  };
  threads = std::max(1u, threads);
  std::vector<std::thread> workers;
  for (unsigned t = 1; t < threads; ++t) workers.emplace_back(trace_rows, t, threads);
  trace_rows(0, threads);
  for (std::thread& worker : workers) worker.join();
  return frame;
}

}  // namespace shadowtiles
