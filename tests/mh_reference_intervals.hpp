// The reference bottom-up MH node intervals of a tile, written independently of the builder from the
// rule in docs/architecture.md §5 (per level, dense, row-major; level L = the texels). Shared by the
// MH and DAG-MH tests, which check their trees' node intervals and their views' coarse levels against it.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
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

// A hierarchy view's (MH, DAG-MH) coarse levels: at every level m each texel of a level-m block reads
// the same value, inside the block's reference interval; with `exact_somewhere` the value is also
// inside the interval of at least one texel of the block. Levels past the last are the full map.
// `what` names the case in failure messages.
template <typename View>
void expect_coarse_levels_inside_reference(const TileIntervals& tile, const View& view, bool exact_somewhere,
                                           const std::string& what) {
  const auto ref = reference_intervals(tile);
  const uint32_t size = tile.size;
  const unsigned L = view.levels();
  for (unsigned m = 0; m <= L; ++m) {
    const uint32_t block = size >> m, side = 1u << m;
    for (uint32_t by = 0; by < side; ++by)
      for (uint32_t bx = 0; bx < side; ++bx) {
        const float value = view.lookup(bx * block, by * block, m);
        EXPECT_TRUE(ref[m][size_t(by) * side + bx].contains(value)) << what << " level " << m;
        bool exact = false;
        for (uint32_t v = by * block; v < (by + 1) * block; ++v)
          for (uint32_t u = bx * block; u < (bx + 1) * block; ++u) {
            ASSERT_EQ(view.lookup(u, v, m), value) << what << " level " << m;
            exact |= tile.at(u, v).contains(value);
          }
        if (exact_somewhere) {
          EXPECT_TRUE(exact) << what << " level " << m;
        }
      }
  }
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) ASSERT_EQ(view.lookup(u, v, L + 5), view.lookup(u, v)) << what;
}

}  // namespace shadowtiles::testing
