// The reference bottom-up MH node intervals of a tile, written independently of the builder from the
// rule in docs/architecture.md §5 (per level, dense, row-major; level L = the texels). Shared by the
// MH and DAG-MH tests, which check their trees' node intervals against it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "builder/depth_interval.hpp"

namespace shadowtiles::testing {

inline std::vector<std::vector<DepthInterval>> reference_intervals(const TileIntervals& tile) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  unsigned L = 0;
  while ((1u << L) < tile.size) ++L;
  std::vector<std::vector<DepthInterval>> levels(L + 1);
  levels[L] = tile.texels;
  for (unsigned l = L; l-- > 0;) {
    const uint32_t side = 1u << l;
    levels[l].resize(size_t(side) * side);
    for (uint32_t y = 0; y < side; ++y)
      for (uint32_t x = 0; x < side; ++x) {
        DepthInterval c[4];
        for (unsigned i = 0; i < 4; ++i) c[i] = levels[l + 1][size_t(2 * y + i / 2) * 2 * side + 2 * x + i % 2];
        // The child lower bound most children contain; the node is the intersection of those children.
        int best = -1, best_count = -1;
        for (int i = 0; i < 4; ++i) {
          int count = 0;
          for (int j = 0; j < 4; ++j) count += c[j].contains(c[i].lower);
          if (count > best_count) best = i, best_count = count;
        }
        DepthInterval r{-kInf, kInf};
        for (int i = 0; i < 4; ++i)
          if (c[i].contains(c[best].lower))
            r.lower = std::max(r.lower, c[i].lower), r.upper = std::min(r.upper, c[i].upper);
        levels[l][size_t(y) * side + x] = r;
      }
  }
  return levels;
}

}  // namespace shadowtiles::testing
