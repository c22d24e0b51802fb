// for_each_overlapping_pair (builder/overlapping_box_pairs.hpp), the cap pass's pair enumeration:
// every pair whose padded boxes overlap is visited exactly once and no other pair, against a
// brute-force check of all pairs. Mixes of box sizes reach each way the grid sizes its cells:
// boxes a texel or more across (cells of 4-256 texels), boxes far smaller than a texel (finer cells,
// down to 1/64 texel), and those with a few boxes as large as the tile (cells coarsened so the
// lists stay short), on windows of 64^2 to 8192^2 texels off the origin.
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <utility>
#include <vector>

#include "builder/overlapping_box_pairs.hpp"

namespace shadowtiles {
namespace {

struct Footprint {
  double lo_u, hi_u, lo_v, hi_v;
};

// Boxes in the window's first `spread` texels each way and around them (some cross the window's
// edges), sides drawn from [min_side, max_side].
std::vector<Footprint> random_boxes(const TexelWindow& window, size_t count, double min_side, double max_side,
                                    uint32_t seed, double spread = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> at(-2.0, (spread > 0 ? spread : window.size) + 2.0), side(min_side, max_side);
  std::vector<Footprint> boxes;
  for (size_t i = 0; i < count; ++i) {
    const double u = window.u0 + at(rng), v = window.v0 + at(rng);
    boxes.push_back({u, u + side(rng), v, v + side(rng)});
  }
  return boxes;
}

void expect_every_overlapping_pair_once(const std::vector<Footprint>& boxes, const TexelWindow& window) {
  std::vector<uint32_t> candidates;
  for (uint32_t i = 0; i < boxes.size(); ++i)
    if (i % 7 != 3) candidates.push_back(i);  // not every footprint is a candidate
  OverlappingBoxPairsScratch scratch;
  std::set<std::pair<uint32_t, uint32_t>> visited;
  size_t visits = 0;
  for_each_overlapping_pair(scratch, boxes, candidates, window, [&](uint32_t i, uint32_t j) {
    ++visits;
    visited.insert({std::min(i, j), std::max(i, j)});
  });
  EXPECT_EQ(visits, visited.size()) << "a pair was visited twice";
  constexpr double kPad = 1.0 / 256;  // the padding the header states
  std::set<std::pair<uint32_t, uint32_t>> expected;
  for (size_t a = 0; a < candidates.size(); ++a)
    for (size_t b = a + 1; b < candidates.size(); ++b) {
      const Footprint& p = boxes[candidates[a]];
      const Footprint& q = boxes[candidates[b]];
      if (p.lo_u - kPad > q.hi_u + kPad || q.lo_u - kPad > p.hi_u + kPad || p.lo_v - kPad > q.hi_v + kPad ||
          q.lo_v - kPad > p.hi_v + kPad)
        continue;
      expected.insert({std::min(candidates[a], candidates[b]), std::max(candidates[a], candidates[b])});
    }
  EXPECT_GT(expected.size(), 0u);
  EXPECT_EQ(visited, expected);
}

TEST(OverlappingBoxPairs, BoxesATexelOrMoreAcross) {
  for (uint32_t size : {64u, 2048u}) {
    const TexelWindow window{3.0 * size, 5.0 * size, size};
    expect_every_overlapping_pair_once(random_boxes(window, 1500, 1.0, 12.0, size), window);
  }
}

TEST(OverlappingBoxPairs, BoxesFarSmallerThanATexel) {
  // ~30 boxes per texel on the small window: the finest cells.
  const TexelWindow small{128, 64, 64};
  expect_every_overlapping_pair_once(random_boxes(small, 3000, 0.001, 0.05, 7), small);
  // The same density in a corner of a large window, whose other cells stay empty; and on a window
  // wider than 4096 texels, whose cells stay at 4 texels (1,024 a side would be coarser).
  const TexelWindow large{0, 0, 2048};
  expect_every_overlapping_pair_once(random_boxes(large, 3000, 0.01, 0.5, 8, 24), large);
  const TexelWindow widest{-8192, 0, 8192};
  expect_every_overlapping_pair_once(random_boxes(widest, 3000, 0.01, 0.5, 11, 24), widest);
}

TEST(OverlappingBoxPairs, TinyBoxesWithAFewAsLargeAsTheTile) {
  const TexelWindow window{64, 0, 64};
  std::vector<Footprint> boxes = random_boxes(window, 2500, 0.002, 0.02, 9);
  const std::vector<Footprint> huge = random_boxes(window, 5, 30.0, 90.0, 10);
  boxes.insert(boxes.end(), huge.begin(), huge.end());
  expect_every_overlapping_pair_once(boxes, window);
}

// Padded boxes that meet or miss by a billionth of a texel, far under a float's step at these
// coordinates, where both round to the same float: the pass prefilters in floats, so it must keep
// every pair that meets by that little (a strict comparison would drop them), and its exact test
// must still drop those that miss.
TEST(OverlappingBoxPairs, BoxesThatMeetOrMissByLessThanAFloatStep) {
  constexpr double kPad = 1.0 / 256;
  for (uint32_t size : {64u, 2048u}) {
    const TexelWindow window{3.0 * size, 5.0 * size, size};
    std::mt19937 rng(size);
    std::uniform_real_distribution<double> at(1.0, size - 3.0);
    std::vector<Footprint> boxes;
    for (int i = 0; i < 400; ++i) {
      const double edge = window.u0 + at(rng), v = window.v0 + at(rng);
      const double gap = (i % 2 ? 1e-9 : -1e-9);  // the next box starts just past or just before the reach
      boxes.push_back({edge - 1.0, edge, v, v + 0.5});
      boxes.push_back({edge + 2 * kPad + gap, edge + 1.0, v + 0.25, v + 0.75});
    }
    expect_every_overlapping_pair_once(boxes, window);
  }
}

}  // namespace
}  // namespace shadowtiles
