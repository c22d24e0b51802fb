// The `surfaces` entry rule's second bound (docs/receiver-contracts.md, "The entry rule", depth
// gaps), for the texels whose square no cover lowered (a mesh border, a hole, a silhouette fold):
// receivers lie within m - b in front of a surface (m: the exit margin, b: the query bias), so a
// point of the square whose surfaces all lie deeper than first hit + m holds no receiver raw lights.
// Then B = the largest depth over the square of every triangle that comes within m of the first hit
// there bounds every surface that matters, and min(first hit, B + tolerance - slack) is a bound as
// the cover's is. Any triangle of the tile counts (closed, open, patches, edge-on): more triangles
// only raise B. Runs once per tile after the rays, on the texels still at their first hit.
// Thread safety: pure function of its arguments.
#pragma once

#include <cstdint>
#include <span>

#include "builder/depth_interval.hpp"
#include "builder/tile_geometry.hpp"

namespace shadowtiles {

// `texels`: the tile's centre-ray intervals (lower = first hit), `entry_lower` the cover pass's
// bounds (lowered in place where the depth gap gives a smaller one), `candidates` the texels (row-major
// indices, ascending) to try: those no cover lowered, whose own first-hit triangle would let them be
// (gap_may_lower). `gap`: the exit margin; `slack`, `tolerance`: DualDepthOptions::entry_slack and
// entry_tolerance (all normalised depth).
void lower_entry_bounds_by_depth_gaps(const TileGeometry& geometry, TileCoord tile, uint32_t size,
                                      std::span<const DepthInterval> texels, std::span<const uint32_t> candidates,
                                      std::span<float> entry_lower, float gap, float slack, float tolerance);

// Whether the depth gap could lower texel (gu, gv) (global texel centre) with first hit `lower` on a
// triangle with `plane`: the first-hit triangle is always in the set, so its own largest depth over
// the square must leave room (on a slope steeper than the slack it does not, and the texel is skipped).
bool gap_may_lower(const DepthPlane& plane, double gu, double gv, float lower, float slack, float tolerance);

}  // namespace shadowtiles
