// Brute-force reference of the exit caps, for `verify` (docs/receiver-contracts.md). Independent of
// the build's fast passes (receiver_surface_caps' row spans and closed form, second_layer_caps'
// triangle pairs): per texel, every triangle whose box touches the square is clipped to the square in
// double precision, and
// - anywhere: the cap is the shallowest clipped point of every surface a shadowed receiver can lie
//   on (open triangles; closed and heightfield triangles not facing the light, patches over nearly
//   closed meshes' holes included);
// - surfaces: the cap is the shallowest point of the second layer inside the square: for every
//   ordered pair (T, T'), T's clipped polygon cut by T''s edges and by z_T - z_T' >= epsilon, and
//   (near cover) by z_T - z_T' >= kSameSurface and z_T >= the texel's lower + near_cover_offset;
//   edge-on triangles cap by their own shallowest point (second_layer_rule.hpp).
// Only texels with an exit are computed, and per texel the triangles are taken shallowest first
// until none can lower the interval, so the result is the exact capped interval.
// Thread safety: pure function.
#pragma once

#include "builder/depth_interval.hpp"
#include "builder/light_space_scene.hpp"
#include "codec/receiver_contract.hpp"

namespace shadowtiles {

struct ReferenceCapStats {
  uint64_t texels = 0;         // texels with an exit, whose cap was computed
  uint64_t clipped = 0;        // triangle-square clips
  uint64_t pair_clips = 0;     // (surfaces) pair regions clipped
};

// `intervals`: the tile's texel-centre intervals (DualDepthRenderer::render_centre); each exit becomes
// max(lower, min(upper, float(cap) - exit_margin)), as the build applies its caps.
void apply_reference_caps(const LightSpaceScene& scene, TileCoord tile, ReceiverContract receivers,
                          double coplanar_epsilon, float exit_margin, TileIntervals& intervals,
                          ReferenceCapStats* stats = nullptr);

}  // namespace shadowtiles
