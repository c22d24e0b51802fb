// GroundTruth: exact visibility of the sun from a world point, by an Embree occlusion ray toward the
// sun over the whole scene (docs/architecture.md §11). The accuracy reference for every method.
// The BVH holds the scene relative to its bounds' centre so float precision follows the scene's
// size, not its distance from the world origin.
// Thread safety: lit() may be called concurrently after construction.
#pragma once

#include "builder/embree_device.hpp"
#include "builder/scene.hpp"

namespace shadowtiles {

// How far toward the sun an occlusion ray starts, per unit of the scene's bounding-box diagonal.
inline constexpr double kGroundTruthOffsetPerDiagonal = 1e-5;
// That offset for a scene with these bounds, in world units.
double ground_truth_offset(const WorldBounds& bounds);

class GroundTruth {
 public:
  // `light_direction`: the direction light travels (toward the scene).
  GroundTruth(const EmbreeDevice& device, const Scene& scene, const Vec3& light_direction);
  // True when nothing lies between `world` and the sun. The ray starts `epsilon` world units toward
  // the sun (default: 1e-5 of the scene diagonal) so the receiver's own surface does not count.
  bool lit(const Vec3& world) const;
  double epsilon() const { return epsilon_; }
  void set_epsilon(double epsilon) { epsilon_ = epsilon; }

 private:
  EmbreeScene scene_;
  Vec3 centre_{};
  Vec3 to_sun_{};
  double epsilon_ = 0;
};

}  // namespace shadowtiles
