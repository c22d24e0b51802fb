// Synthetic interval tiles for the MH tests and benchmarks: deterministic (seeded) stand-ins for
// dual-depth output with the features that matter for compression (smooth surfaces, edges,
// zero-width intervals of open geometry, wide intervals of closed objects, misses).
// Thread safety: pure function.
#pragma once

#include <cstdint>

#include "builder/depth_interval.hpp"

namespace shadowtiles {

enum class MhSyntheticKind {
  random_intervals,  // independent random intervals per texel, some misses, some zero-width
  noisy_plane,       // tilted plane + small noise, zero-width (open surface)
  closed_plane,      // tilted plane + noise with a thickness (closed solid): wide intervals
  steps,             // axis-aligned boxes of constant depth (buildings) over a ground plane
  all_miss,          // nothing hit: [1, +inf) everywhere
  boxes_and_misses,  // closed boxes floating over nothing: box intervals and misses
};

// Every kind, for tests that sweep them all.
inline constexpr MhSyntheticKind kEveryMhSyntheticKind[] = {
    MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane, MhSyntheticKind::closed_plane,
    MhSyntheticKind::steps,            MhSyntheticKind::all_miss,    MhSyntheticKind::boxes_and_misses};

TileIntervals make_synthetic_tile(MhSyntheticKind kind, uint32_t size, uint64_t seed);
const char* synthetic_kind_name(MhSyntheticKind kind);

}  // namespace shadowtiles
