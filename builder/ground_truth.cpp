#include "builder/ground_truth.hpp"

#include <cmath>
#include <limits>

#include "builder/embree_world_scene.hpp"

namespace shadowtiles {

double ground_truth_offset(const WorldBounds& bounds) {
  double diagonal = 0;
  for (int i = 0; i < 3; ++i) diagonal += std::pow(bounds.max[i] - bounds.min[i], 2);
  return kGroundTruthOffsetPerDiagonal * std::sqrt(diagonal);
}

GroundTruth::GroundTruth(const EmbreeDevice& device, const Scene& scene, const Vec3& light_direction)
    : scene_(rtcNewScene(device.get())) {
  centre_ = scene_centre(scene);
  double length = std::sqrt(light_direction[0] * light_direction[0] + light_direction[1] * light_direction[1] +
                            light_direction[2] * light_direction[2]);
  for (int i = 0; i < 3; ++i) to_sun_[i] = -light_direction[i] / length;
  epsilon_ = ground_truth_offset(scene.bounds);

  commit_world_triangles(device, scene_, scene, centre_);
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
