// Brute-force reference of the `surfaces` entry rule (docs/receiver-contracts.md, "The entry rule"),
// for `verify`: independent of the renderer's pass, which looks at the first hit's triangle and the
// one across an edge crossing the square, through their tile-local float footprints. Here every
// triangle of the tile whose footprint (double light-space vertices, closed) contains a texel's whole
// square bounds the visible depth there by its own deepest corner, and so does every pair of
// triangles on the two sides of a shared edge whose union contains it (each triangle's deepest point
// over its own part of the square); the bound is min(first hit, the smallest such depth + tolerance -
// slack), rounded up to a float. The renderer's covers are among these and its depths over the whole
// square are no smaller, so the reference is at most the renderer's bound (up to rounding) and a
// value the build stores is never below it.
// Patches (nearly closed meshes' holes) are not surfaces and bound nothing; edge-on triangles neither.
// Thread safety: pure function.
#pragma once

#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/light_space_scene.hpp"

namespace shadowtiles {

// `first_hits`: the tile's texel-centre intervals (DualDepthRenderer::render_centre; lower = the
// first hit). `slack`, `tolerance`: DualDepthOptions::entry_slack and entry_tolerance. Returns one
// bound per texel, row-major; a miss keeps its lower (1).
std::vector<float> reference_entry_bounds(const LightSpaceScene& scene, TileCoord tile, const TileIntervals& first_hits,
                                          double slack, double tolerance);

}  // namespace shadowtiles
