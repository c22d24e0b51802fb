// DAG-MH batch lookups against the per-query ones, on synthetic tiles for every treelet height and
// skip-list level: lit_sorted == threshold <= lookup(), pcf_count_sorted == pcf_lit_count() for
// every box corner of the tile in Morton order (boxes sharing descents), for sparse sorted subsets
// (descents resuming from far-apart paths), for dense corners shuffled inside 4x4 groups and for
// unsorted corners, kernels 1..8.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_synthetic.hpp"
#include "codec/morton.hpp"
#include "codec/dagmh_decoder.hpp"

namespace shadowtiles {
namespace {

const MhSyntheticKind kKinds[] = {MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane,
                                  MhSyntheticKind::closed_plane, MhSyntheticKind::steps,
                                  MhSyntheticKind::all_miss, MhSyntheticKind::boxes_and_misses};

// Corners of every k x k box inside a size^2 tile, in Morton order, each with a random threshold
// drawn around the tile's depths (so boxes straddle shadow edges).
std::vector<TexelQuery> morton_corners(uint32_t size, uint32_t k, std::mt19937& rng) {
  std::vector<std::pair<uint64_t, TexelQuery>> keyed;
  std::uniform_real_distribution<float> depth(0.0f, 1.0f);
  for (uint32_t v = 0; v + k <= size; ++v)
    for (uint32_t u = 0; u + k <= size; ++u) keyed.push_back({morton_encode(u, v), TexelQuery{u, v, depth(rng)}});
  std::sort(keyed.begin(), keyed.end(), [](auto& a, auto& b) { return a.first < b.first; });
  std::vector<TexelQuery> out;
  for (auto& [key, q] : keyed) out.push_back(q);
  return out;
}

void expect_batch_equals_single(const DagMhTileView& view, const std::vector<TexelQuery>& corners, uint32_t k,
                                const char* what) {
  std::vector<uint32_t> counts(corners.size(), ~0u);
  view.pcf_count_sorted(corners, k, counts.data());
  for (size_t i = 0; i < corners.size(); ++i) {
    const uint32_t expected = view.pcf_lit_count(corners[i].u, corners[i].v, k, k, corners[i].threshold, 0.0f);
    ASSERT_EQ(counts[i], expected) << what << " k" << k << " corner " << corners[i].u << "," << corners[i].v;
  }
  if (k == 1) {
    std::vector<uint8_t> lit(corners.size(), 2);
    view.lit_sorted(corners, kDagMhAllLevels, lit.data());
    for (size_t i = 0; i < corners.size(); ++i)
      ASSERT_EQ(lit[i], corners[i].threshold <= view.lookup(corners[i].u, corners[i].v) ? 1 : 0) << what << " point " << i;
  }
}

TEST(DagMhBatch, SortedPcfCountsEqualPerBoxCountsForEveryTreeletHeightAndSkipLevel) {
  constexpr uint32_t kSize = 128;
  uint64_t straddling = 0;
  for (MhSyntheticKind kind : kKinds) {
    const TileIntervals tile = make_synthetic_tile(kind, kSize, 7);
    auto hierarchy = build_mh(tile);
    ASSERT_TRUE(hierarchy.ok());
    for (unsigned height = 2; height <= 5; ++height) {
      DagMhOptions options;
      options.treelet_height = height;
      auto bytes = encode_dagmh(*hierarchy, options);
      ASSERT_TRUE(bytes.ok()) << bytes.error().message;
      for (unsigned skip : {0u, 3u, 6u}) {
        DagMhParseOptions parse;
        parse.skip_level = skip;
        auto view = DagMhTileView::parse(*bytes, parse);
        ASSERT_TRUE(view.ok()) << view.error().message;
        std::mt19937 rng(height * 10 + skip);
        for (uint32_t k : {1u, 2u, 3u, 5u, 8u}) {
          const std::vector<TexelQuery> all = morton_corners(kSize, k, rng);
          const std::string what = std::string(synthetic_kind_name(kind)) + " H" + std::to_string(height) + " skip" +
                                   std::to_string(skip);
          expect_batch_equals_single(*view, all, k, (what + " dense").c_str());
          // Sparse: one corner in 37, still sorted, so consecutive boxes share little of their paths.
          std::vector<TexelQuery> sparse;
          for (size_t i = 0; i < all.size(); i += 37) sparse.push_back(all[i]);
          expect_batch_equals_single(*view, sparse, k, (what + " sparse").c_str());
          // Dense, sorted by 4x4-texel groups only and shuffled inside each (the order query_batch
          // hands the decoders: its sort stops at about 4 points per group).
          std::vector<TexelQuery> grouped = all;
          for (size_t g = 0; g < grouped.size(); g += 16)
            std::shuffle(grouped.begin() + g, grouped.begin() + std::min(grouped.size(), g + 16), rng);
          expect_batch_equals_single(*view, grouped, k, (what + " grouped").c_str());
          // Unsorted: still answered correctly.
          std::vector<TexelQuery> shuffled = sparse;
          std::shuffle(shuffled.begin(), shuffled.end(), rng);
          expect_batch_equals_single(*view, shuffled, k, (what + " shuffled").c_str());
          if (k == 3)
            for (const TexelQuery& c : sparse) {
              const uint32_t n = view->pcf_lit_count(c.u, c.v, k, k, c.threshold, 0.0f);
              straddling += n != 0 && n != k * k;
            }
        }
      }
    }
  }
  EXPECT_GT(straddling, 1000u) << "the thresholds must put boxes across shadow edges";
}

}  // namespace
}  // namespace shadowtiles
