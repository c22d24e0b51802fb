// PCF over an MH/MMH tile: the LCA + last-node-cache path equals naive per-sample lookups.
#include <gtest/gtest.h>

#include <random>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mmh_merger.hpp"
#include "tests/mh_tile_views.hpp"
#include "codec/mh_decoder.hpp"

namespace shadowtiles {
namespace {

uint32_t naive_count(const MhTileView& view, uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float depth,
                     float bias) {
  uint32_t lit = 0;
  for (uint32_t v = v0; v < v0 + kh; ++v)
    for (uint32_t u = u0; u < u0 + kw; ++u) lit += depth <= view.lookup(u, v) + bias;
  return lit;
}

TEST(MhPcf, FastPathEqualsNaive) {
  std::mt19937 rng(7);
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane,
                               MhSyntheticKind::steps, MhSyntheticKind::boxes_and_misses, MhSyntheticKind::all_miss}) {
    for (uint32_t size : {1u, 4u, 64u, 256u}) {
      MhTileViews views;
      make_mh_tile_views(make_synthetic_tile(kind, size, size * 3 + 1), {0u, 2u, 6u}, views);
      ASSERT_FALSE(HasFatalFailure());
      for (const MhTileViews::Entry& entry : views.views) {
        const MhTileView* view = &entry.view;
        for (int trial = 0; trial < 300; ++trial) {
          const uint32_t k = std::min<uint32_t>(size, std::vector<uint32_t>{1, 2, 3, 5, 7, 9, 16}[trial % 7]);
          const uint32_t kh = trial % 5 == 0 ? std::max(1u, k / 2) : k;  // some rectangles (split kernels)
          const uint32_t u0 = rng() % (size - k + 1), v0 = rng() % (size - kh + 1);
          // Depth near a real value so both outcomes occur.
          const float depth = view->lookup(u0 + k / 2, v0 + kh / 2) + (float(rng() % 200) - 100.0f) * 1e-4f;
          const float bias = trial % 3 == 0 ? 0.0f : 1e-3f;
          ASSERT_EQ(view->pcf_lit_count(u0, v0, k, kh, depth, bias), naive_count(*view, u0, v0, k, kh, depth, bias))
              << synthetic_kind_name(kind) << " size " << size << " at " << u0 << "," << v0 << " k " << k;
          if (kh == k) {
            ASSERT_EQ(view->pcf_lit_fraction(u0, v0, k, depth, bias),
                      float(naive_count(*view, u0, v0, k, k, depth, bias)) / float(k * k));
          }
        }
      }
    }
  }
}

// Every kernel position of a small tile, all kernel sizes: exhaustive agreement.
TEST(MhPcf, ExhaustiveOnSmallTile) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::random_intervals, 32, 11);
  auto tree = build_mh(tile);
  ASSERT_TRUE(tree.ok());
  auto bytes = encode_mh(*tree);
  auto view = MhTileView::parse(*bytes);
  ASSERT_TRUE(view.ok());
  for (uint32_t k = 1; k <= 32; k += 2)
    for (uint32_t v0 = 0; v0 + k <= 32; ++v0)
      for (uint32_t u0 = 0; u0 + k <= 32; ++u0)
        for (float depth : {0.25f, 0.5f, 0.75f})
          ASSERT_EQ(view->pcf_lit_count(u0, v0, k, k, depth, 0.0f), naive_count(*view, u0, v0, k, k, depth, 0.0f));
}

}  // namespace
}  // namespace shadowtiles
