// Receiver-surface exit caps (`build --exit-caps`, STABILITY.md finding 1, issue #8).
// Receivers lie anywhere in a texel, not only on its centre's ray: near a silhouette or a crease, a
// shadowed surface other than the centre ray's exit triangle can sit, within the texel, at a depth
// between the centre ray's entry and exit (the back of a bust just inside its outline, the far slope
// of a ridge at a grazing sun). Such a receiver must stay shadowed, so each texel's exit is capped by
// the shallowest depth, within the texel's square, of every surface a shadowed receiver can lie on:
// closed or heightfield triangles facing away from the light (or edge-on), and open triangles; patches
// over nearly closed meshes' holes (Scene::patch_triangles) as closed triangles.
// The depth is exact: depth is linear on a triangle, so its minimum over (triangle ∩ square) is at a
// vertex of the clipped polygon. Computed in the scene's double light-space coordinates (global
// texels), so the result does not depend on the tiling.
// Speed: only the texels a triangle touches are visited (row spans); texels crossed by an edge or
// holding a vertex are clipped (Sutherland-Hodgman), texels inside the triangle take the plane's
// value at the square's shallowest corner. Both give the float the per-texel clipping of every
// texel gives, bit for bit (see receiver_surface_caps.cpp for why).
// Thread safety: pure functions.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/light_space_scene.hpp"

namespace shadowtiles {

// How the texels were resolved (tests check the fast path is taken; the report prints them).
struct ReceiverCapCounts {
  uint64_t clipped = 0;    // texels near an edge or a vertex: exact clipping
  uint64_t interior = 0;   // texels inside the triangle: closed form
  uint64_t fallback = 0;   // interior texels whose closed form sat too close to a float rounding
                           // boundary to be sure, clipped instead (counted in `interior` too)
  uint64_t already_lower = 0;  // of those to clip, texels whose cap was already at or below the
                               // triangle's shallowest vertex: left as they were, unclipped
  uint64_t corner = 0;         // of those to clip (counted in `clipped`), texels whose shallowest
                               // square corner lies inside the triangle: closed form, unclipped
  uint64_t chord = 0;          // ... crossed by one edge only, that corner outside: the edge's chord
  uint64_t triangles_skipped = 0;  // with the tile's intervals given: triangles near no texel that
                                   // takes a cap, not rasterised (their texels are not counted above)

  void add(const ReceiverCapCounts& other) {
    clipped += other.clipped, interior += other.interior, fallback += other.fallback;
    already_lower += other.already_lower, corner += other.corner, chord += other.chord;
    triangles_skipped += other.triangles_skipped;
  }
};

// A square window of texels: texel (i, j) covers global texels [u0 + i, u0 + i + 1] x [v0 + j, ...].
struct TexelWindow {
  double u0 = 0, v0 = 0;
  uint32_t size = 0;
};

// Lowers cap[j * size + i] to the shallowest depth of triangle (a, b, c) within texel (i, j)'s square,
// for every texel of the window whose closed square the triangle touches (a triangle starting exactly on
// a texel border, the window's own included, touches the texel before that border too).
void lower_caps_by_triangle(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c,
                            const TexelWindow& window, std::span<float> cap, ReceiverCapCounts* counts = nullptr);

// The cap per texel of `tile` (+inf where nothing limits it), over the tile's triangles that a
// shadowed receiver can lie on. `storage`: a buffer to reuse (its pages already mapped), e.g. the
// previous tile's caps.
// With `intervals` (the tile's, from the renderer), only the caps apply_exit_caps reads are computed:
// a triangle whose texels (its rasterised box) hold no interval that takes a cap is skipped, so other
// texels may keep +inf or a higher cap. Under `anywhere` on open meshes nearly every hit is a point
// interval, which no cap changes, and only the solids' texels take one.
std::vector<float> receiver_surface_caps(const LightSpaceScene& scene, TileCoord tile,
                                         ReceiverCapCounts* counts = nullptr, std::vector<float> storage = {},
                                         const TileIntervals* intervals = nullptr);

// Whether apply_exit_caps lowers this interval's upper bound to a cap: an exit below a hit. A point
// interval (open geometry under `anywhere`) or a miss keeps its bounds whatever the cap.
inline bool takes_exit_cap(const DepthInterval& interval) {
  return interval.upper > interval.lower && interval.lower < 1.0f;
}

}  // namespace shadowtiles
