// MH/MMH batch point lookups against the per-query ones: lit_sorted == threshold <= lookup() for
// dense Morton-sorted queries (shared descents) and for sparse ones spread over deep trees (the
// interleaved walks with prefetch), for every skip-list level, MH and MMH, for dense input shuffled
// inside small groups (query_batch's order) and for unsorted input.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "builder/mh_synthetic.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/morton.hpp"
#include "tests/mh_tile_views.hpp"

namespace shadowtiles {
namespace {

enum class Order { sorted, grouped, unsorted };

// `count` random texels of a size^2 tile in `order` (Morton), thresholds near the stored values.
std::vector<TexelQuery> queries(const MhTileView& view, uint32_t size, size_t count, Order order, std::mt19937& rng) {
  std::vector<std::pair<uint64_t, TexelQuery>> keyed;
  for (size_t i = 0; i < count; ++i) {
    const uint32_t u = rng() % size, v = rng() % size;
    const float threshold = view.lookup(u, v) + (float(rng() % 200) - 100.0f) * 1e-4f;
    keyed.push_back({morton_encode(u, v), TexelQuery{u, v, threshold}});
  }
  if (order != Order::unsorted) std::sort(keyed.begin(), keyed.end(), [](auto& a, auto& b) { return a.first < b.first; });
  if (order == Order::grouped)  // shuffled inside runs of 16 (query_batch stops its sort at ~4 per group)
    for (size_t g = 0; g < keyed.size(); g += 16)
      std::shuffle(keyed.begin() + g, keyed.begin() + std::min(keyed.size(), g + 16), rng);
  std::vector<TexelQuery> out;
  for (auto& [key, q] : keyed) out.push_back(q);
  return out;
}

TEST(MhBatch, SortedAndSparseBatchesEqualPerQueryLookups) {
  constexpr uint32_t kSize = 1024;  // 10 levels: deep enough below every skip level for sparse walks
  std::mt19937 rng(11);
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane,
                               MhSyntheticKind::steps, MhSyntheticKind::boxes_and_misses}) {
    MhTileViews views;
    make_mh_tile_views(make_synthetic_tile(kind, kSize, 5), {0u, 3u, 6u}, views);
    ASSERT_FALSE(HasFatalFailure());
    for (const MhTileViews::Entry& entry : views.views) {
      const MhTileView* view = &entry.view;
      const unsigned skip = entry.skip;
      // 300 points over 1M texels: sparse (interleaved walks); 20,000: dense (shared descents), also
      // shuffled inside groups of 16; 2,000 unsorted; 9 (below the sparse test's minimum); and
      // coarser levels.
      for (auto [count, order] : {std::pair{300u, Order::sorted}, {20000u, Order::sorted}, {20000u, Order::grouped},
                                  {2000u, Order::unsorted}, {9u, Order::sorted}}) {
        const std::vector<TexelQuery> q = queries(*view, kSize, count, order, rng);
        for (unsigned max_level : {kMhAllLevels, 9u, 7u}) {
          std::vector<uint8_t> lit(q.size(), 2);
          view->lit_sorted(q, max_level, lit.data());
          for (size_t i = 0; i < q.size(); ++i)
            ASSERT_EQ(lit[i], q[i].threshold <= view->lookup(q[i].u, q[i].v, max_level) ? 1 : 0)
                << synthetic_kind_name(kind) << (entry.merged ? " MMH" : " MH") << " skip " << skip << " count " << count << " level " << max_level
                << " query " << i;
        }
      }
    }
  }
}

// Batch PCF (pcf_count_sorted) against per-box counts (pcf_lit_count) and per-sample lookups, for
// every skip level. Boxes crossing a skip list cell are counted in parts from their cells' entries;
// the batch's first boxes are such boxes here (corners one texel before a level-3 cell's edge), so
// the shared-path walk starts after boxes that never walked.
TEST(MhBatch, SortedPcfBoxesEqualPerBoxCounts) {
  constexpr uint32_t kSize = 256;
  std::mt19937 rng(5);
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane,
                               MhSyntheticKind::steps}) {
    MhTileViews views;
    // Deepest skip list first: a box walking from a stale path would then not find the root state
    // a skip-0 view's batch left in the same stack slot (which happens to be right).
    make_mh_tile_views(make_synthetic_tile(kind, kSize, 9), {6u, 3u, 0u}, views);
    ASSERT_FALSE(HasFatalFailure());
    for (const MhTileViews::Entry& entry : views.views) {
      const MhTileView& view = entry.view;
      for (uint32_t k : {3u, 5u, 1u}) {
        std::vector<TexelQuery> corners;
        for (uint32_t c = 31; c + k <= kSize && corners.size() < 4; c += 32)  // across cells first
          corners.push_back({c, c, view.lookup(c, c)});
        std::vector<TexelQuery> rest = queries(view, kSize - k + 1, 3000, Order::sorted, rng);
        corners.insert(corners.end(), rest.begin(), rest.end());
        std::vector<uint32_t> counts(corners.size(), ~0u);
        view.pcf_count_sorted(corners, k, counts.data());
        for (size_t i = 0; i < corners.size(); ++i) {
          const TexelQuery& c = corners[i];
          uint32_t lit = 0;
          for (uint32_t v = c.v; v < c.v + k; ++v)
            for (uint32_t u = c.u; u < c.u + k; ++u) lit += c.threshold <= view.lookup(u, v);
          ASSERT_EQ(view.pcf_lit_count(c.u, c.v, k, k, c.threshold, 0.0f), lit)
              << synthetic_kind_name(kind) << " skip " << entry.skip << " k " << k << " box " << i;
          ASSERT_EQ(counts[i], lit) << synthetic_kind_name(kind) << (entry.merged ? " MMH" : " MH") << " skip "
                                    << entry.skip << " k " << k << " box " << i;
        }
      }
    }
  }
}

}  // namespace
}  // namespace shadowtiles
