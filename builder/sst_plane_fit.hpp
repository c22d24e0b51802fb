// SST plane fit: a quantised plane d(x, y) (codec/sst_format.hpp) that stays inside [lower, upper]
// for every texel of a square region of a tile, or nothing when none is found.
//
// Finding a plane inside all intervals is a 3-variable LP feasibility problem. We solve it
// heuristically but soundly: weighted least squares on interval midpoints (weight 1/width^2, so
// narrow intervals pull hardest) gives the slopes, the offset is then centred exactly between the
// tightest lower and upper constraints, and texels the plane still misses are up-weighted for a few
// rounds (L-infinity by reweighting). The slopes and offset are then quantised and EVERY texel is
// re-checked with the decoder's exact float expression; only a plane that passes is returned. A
// missed plane costs size (the caller subdivides), never correctness.
// Thread safety: pure function (per-thread scratch).
#pragma once

#include <cstdint>
#include <optional>

#include "builder/depth_interval.hpp"
#include "codec/sst_format.hpp"

namespace shadowtiles {

// Region: texels [x0, x0 + side) x [y0, y0 + side) of `intervals`; the plane's (0, 0) is (x0, y0).
// Precondition: the region lies inside the tile, side >= 1.
std::optional<sst_format::PlaneBits> fit_sst_plane(const TileIntervals& intervals, uint32_t x0, uint32_t y0,
                                                   uint32_t side);

// True when `plane` puts every texel of the region inside its interval (the decoder's arithmetic).
bool sst_plane_fits(const TileIntervals& intervals, uint32_t x0, uint32_t y0, uint32_t side,
                    const sst_format::PlaneBits& plane);

}  // namespace shadowtiles
