// The dual depth of one tile: per texel the interval [lower, upper] of normalised light-space depth
// (0 = near plane, 1 = far plane) such that any value inside gives every receiver the same shadow
// answer as the exact entry depth (docs/architecture.md §4). Misses are [1, +inf): fully lit.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace shadowtiles {

struct DepthInterval {
  float lower = 1.0f;
  float upper = std::numeric_limits<float>::infinity();

  bool contains(float value) const { return value >= lower && value <= upper; }
};

// A square tile of side `size` texels, row-major: texel (u, v) is texels[v * size + u].
struct TileIntervals {
  uint32_t size = 0;
  std::vector<DepthInterval> texels;
  // The `surfaces` entry rule's bound per texel (DualDepthOptions::entry_slack), row-major, kept
  // apart from `lower` (the first hit, which raw stores); empty when the rule is off or applied
  // (apply_entry_rule in builder/dual_depth_renderer.hpp).
  std::vector<float> entry_lower = {};

  const DepthInterval& at(uint32_t u, uint32_t v) const { return texels[size_t(v) * size + u]; }
  DepthInterval& at(uint32_t u, uint32_t v) { return texels[size_t(v) * size + u]; }
  // True when every texel is a miss: such a tile is empty and is not stored.
  bool all_missed() const {
    for (const auto& t : texels)
      if (t.lower < 1.0f) return false;
    return true;
  }
};

// lower = min(lower, entry_lower) per texel, then entry_lower is emptied (nothing to do when empty).
// After it, lower is no longer the first hit: raw and the other first-hit methods are encoded from
// the intervals before, the interval methods (MH, MMH, DAG-MH, CPVS) after (build_mh takes the min
// itself as it reads an unapplied tile).
inline void apply_entry_rule(TileIntervals& intervals) {
  if (intervals.entry_lower.empty()) return;
  for (size_t i = 0; i < intervals.texels.size(); ++i)
    intervals.texels[i].lower = std::min(intervals.texels[i].lower, intervals.entry_lower[i]);
  intervals.entry_lower.clear();
}

}  // namespace shadowtiles
