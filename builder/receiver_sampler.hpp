// Receiver points sampled uniformly over the scene's surface area (triangles chosen by area, points
// uniform inside them), with their geometric normals: the receivers accuracy is measured on.
// Deterministic for a seed. Thread safety: pure function.
#pragma once

#include <cstdint>
#include <vector>

#include "builder/scene.hpp"

namespace shadowtiles {

struct Receiver {
  Vec3 position;
  Vec3 normal;  // unit, counter-clockwise front face
  uint32_t triangle = 0;
};

std::vector<Receiver> sample_receivers(const Scene& scene, size_t count, uint64_t seed);

}  // namespace shadowtiles
