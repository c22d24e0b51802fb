// The definitions the `surfaces` receiver contract's caps share between the build's fast pass
// (second_layer_caps) and verify's brute-force reference (reference_caps): what counts as one
// surface and which triangles have no projected area. Only definitions live here, no algorithm, so
// the two implementations stay independent. docs/receiver-contracts.md states the rule.
#pragma once

#include <algorithm>
#include <cmath>

#include "codec/light_frame.hpp"

namespace shadowtiles::second_layer {

// Surfaces closer than this in depth (normalised) at the same (u, v) are the same surface at any
// depth: faces that coincide up to rounding. (Ground truth's occlusion rays start 1e-5 of the scene
// diagonal off the receiver, more than this, so what they find shadowed is covered by more.)
inline constexpr double kSameSurface = 1e-6;

// Surfaces closer than this in depth (normalised) at the same (u, v) are one surface near the first
// hit: coplanar duplicates (IFC double faces, decals, a closed box's bottom on the floor). The
// contract's value is the query bias (raw, the first-hit map, cannot tell them apart either), floored
// so a zero bias still merges faces that coincide up to rounding.
inline double coplanar_epsilon(double bias_depth) { return std::max(bias_depth, kSameSurface); }

// Near cover: a point covered by another surface by at least kSameSurface but less than the coplanar
// epsilon is in the second layer where it lies deeper than the texel's lower + this offset. Raw
// shadows a receiver only deeper than lower + bias, and the offset is at most the bias
// (eps = max(bias, kSameSurface)), so every receiver raw and the truth both shadow stays shadowed
// (docs/receiver-contracts.md, "near cover").
inline double near_cover_offset(double coplanar_epsilon) { return std::max(0.0, coplanar_epsilon - kSameSurface); }

// Twice the projected (u, v) area, signed (negative: faces the light).
inline double projected_area2(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
}

// Parallel to the light, up to cancellation: the triangle covers no area, so it hides nothing; its
// own points lie under its shallowest one along the light, so it is treated as shadowed below that
// point (it caps by its shallowest point in the texel, as under `anywhere`).
inline bool edge_on(const LightSpacePoint& a, const LightSpacePoint& b, const LightSpacePoint& c) {
  const double scale = std::fabs((b.u - a.u) * (c.v - a.v)) + std::fabs((b.v - a.v) * (c.u - a.u));
  return !(std::fabs(projected_area2(a, b, c)) > 1e-9 * scale);
}

}  // namespace shadowtiles::second_layer
