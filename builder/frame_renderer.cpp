#include "builder/frame_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

#include "builder/embree_world_scene.hpp"

namespace shadowtiles {

uint64_t FrameHits::hit_count() const {
  return uint64_t(std::count_if(pixels.begin(), pixels.end(), [](const PrimaryHit& p) { return p.hit; }));
}

FrameRenderer::FrameRenderer(const EmbreeDevice& device, const Scene& scene) : scene_(rtcNewScene(device.get())) {
  centre_ = scene_centre(scene);
  commit_world_triangles(device, scene_, scene, centre_);
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
        RTCRayHit ray = world_ray(eye, dir);
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
