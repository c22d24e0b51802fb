// The whole scene as one Embree triangle geometry, for rays traced in world space (ground truth,
// camera frames). Vertices are stored relative to `centre` (float precision stays at the scene's
// own scale however far it lies from the origin); callers offset ray origins the same way.
// Thread safety: call before the scene is traced; the committed scene may then be traced concurrently.
#pragma once

#include "builder/embree_device.hpp"
#include "builder/scene.hpp"

namespace shadowtiles {

// The centre of the scene's bounds: the origin of the Embree coordinates.
Vec3 scene_centre(const Scene& scene);
// Adds every triangle of `scene` (robust traversal) and commits `target`.
void commit_world_triangles(const EmbreeDevice& device, const EmbreeScene& target, const Scene& scene,
                            const Vec3& centre);

}  // namespace shadowtiles
