// Which receivers lie inside a solid: the places no receiver contract covers (docs/receiver-contracts.md:
// "faces inside closed solids are not receivers", under `anywhere` and `surfaces` alike). A method may
// answer anything there, so the accuracy evaluator leaves such receivers out for every method, raw
// included, and reports how many (a window pane running through its frame's mullion, a beam end
// buried in a wall).
// The solid is the one the dual-depth renderer counts (builder/dual_depth_renderer.hpp): closed
// meshes and heightfields (solid below), and nearly closed meshes with their patches when the scene
// was loaded with them. The accuracy evaluator loads scenes without them: a nearly closed mesh is the
// build's guess, so receivers its patches enclose stay in the count, where a wrong guess shows as a leak. A receiver is inside when that counter, walked from the sun down to it, is positive:
// crossing a surface facing the light enters (+1), one facing away leaves (-1). The receiver is first
// moved off its own surface along its normal, so a point on a solid's outer face is outside.
// Thread safety: pure function (one Embree scene per call).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "builder/embree_device.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene.hpp"

namespace shadowtiles {

// 1 per receiver inside a solid. `light_direction`: the direction light travels.
std::vector<uint8_t> receivers_inside_solids(const EmbreeDevice& device, const Scene& scene,
                                             const Vec3& light_direction, std::span<const Receiver> receivers);

// Removes the receivers inside solids (keeping the others' order); returns how many it removed.
size_t drop_receivers_inside_solids(const EmbreeDevice& device, const Scene& scene, const Vec3& light_direction,
                                    std::vector<Receiver>& receivers);

}  // namespace shadowtiles
