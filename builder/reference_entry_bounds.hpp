// Brute-force reference of the `surfaces` entry rule (docs/receiver-contracts.md, "The entry rule"),
// for `verify`, independent of the renderer's pass (which grows a cover from the first hit's triangle
// across shared edges, through tile-local float footprints, and bounds each triangle by its plane over
// the whole square). Here, per texel: every triangle of the tile with area in the square (double
// light-space vertices) is clipped to it and weighed by its deepest point over its part; the bound is
// the smallest depth B such that the triangles no deeper than B cover the square (the square less
// those triangles, piece by convex piece, leaves nothing but slivers of under 1e-9 texels squared),
// then min(first hit, B + tolerance - slack), rounded up to a float. The renderer's cover is such a
// set and its depths are no smaller, so the reference is at most the renderer's bound (up to rounding)
// and a value the build stores is never below it. Patches (nearly closed meshes' holes) are not
// surfaces and cover nothing; edge-on triangles neither.
// The depth-gap bound beside it (builder/entry_depth_gap.hpp): G = the largest depth over the square
// of every triangle (edge-on ones too, by their vertices) whose part of the square comes within `gap`
// of the first hit, clipped exactly here where the renderer bounds planes over the whole square; the
// texel's bound is min(first hit, min(B, G) + tolerance - slack).
// Thread safety: pure function.
#pragma once

#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/light_space_scene.hpp"

namespace shadowtiles {

// `first_hits`: the tile's texel-centre intervals (DualDepthRenderer::render_centre; lower = the
// first hit). `slack`, `tolerance`: DualDepthOptions::entry_slack and entry_tolerance; `gap`: the
// exit margin (normalised depth). Returns one bound per texel, row-major; a miss keeps its lower (1).
std::vector<float> reference_entry_bounds(const LightSpaceScene& scene, TileCoord tile, const TileIntervals& first_hits,
                                          double slack, double tolerance, double gap);

}  // namespace shadowtiles
