// MMH merging: exhaustive losslessness of every sharer, coarse levels, size never above MH, forced
// hash collisions still exact.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>
#include <utility>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mh_verify.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/mh_decoder.hpp"

namespace shadowtiles {
namespace {

constexpr auto& kKinds = kEveryMhSyntheticKind;

struct Built {
  std::vector<uint8_t> mh_bytes, mmh_bytes;
  MhTileView mh, mmh;
  MmhMergeStats stats;
};

Built build_both(const TileIntervals& tile, MmhMergeOptions options = {},
                 MhConstruction construction = MhConstruction::bottom_up) {
  Built b;
  auto tree = build_mh(tile, {construction});
  EXPECT_TRUE(tree.ok());
  auto merged = merge_mmh(*tree, options, &b.stats);
  EXPECT_TRUE(merged.ok()) << (merged.ok() ? "" : merged.error().message);
  b.mh_bytes = *encode_mh(*tree);
  b.mmh_bytes = *encode_mh(*merged);
  auto mh = MhTileView::parse(b.mh_bytes);
  auto mmh = MhTileView::parse(b.mmh_bytes);
  EXPECT_TRUE(mh.ok());
  EXPECT_TRUE(mmh.ok()) << (mmh.ok() ? "" : mmh.error().message);
  if (mh.ok()) b.mh = *mh;
  if (mmh.ok()) b.mmh = *mmh;
  return b;
}

using Param = std::tuple<MhSyntheticKind, uint32_t>;
class MmhLossless : public ::testing::TestWithParam<Param> {};

TEST_P(MmhLossless, EverySharerExactAndNeverLarger) {
  const auto [kind, size] = GetParam();
  const TileIntervals tile = make_synthetic_tile(kind, size, 99 + size);
  for (MhConstruction construction : {MhConstruction::bottom_up, MhConstruction::top_down}) {
    if (construction == MhConstruction::top_down && size > 256) continue;
    Built b = build_both(tile, {}, construction);
    MhVerifyReport report;
    Status s = verify_lossless(tile, b.mmh, &report);
    EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
    EXPECT_EQ(report.violations, 0u);
    EXPECT_LE(b.mmh_bytes.size(), b.mh_bytes.size());
    EXPECT_LE(b.stats.blocks_after, b.stats.blocks_before - b.stats.merges);  // a merge drops a whole subtree
    EXPECT_EQ(b.mmh.stats().blocks, b.stats.blocks_after);
    if (b.stats.merges > 0) {
      EXPECT_TRUE(b.mmh.stats().merged);
      EXPECT_GT(b.mmh.stats().block_references, b.mmh.stats().blocks);
    }
  }
}

std::string param_name(const ::testing::TestParamInfo<Param>& info) {
  return std::string(synthetic_kind_name(std::get<0>(info.param))) + "_" + std::to_string(std::get<1>(info.param));
}

INSTANTIATE_TEST_SUITE_P(Synthetic, MmhLossless,
                         ::testing::Combine(::testing::ValuesIn(kKinds),
                                            ::testing::Values(1u, 2u, 4u, 16u, 64u, 256u, 512u)),
                         param_name);

// Structured inputs share a lot: the merge must actually happen (guards against a merger that
// silently never merges).
TEST(Mmh, StructuredInputsShrink) {
  for (MhSyntheticKind kind : {MhSyntheticKind::steps, MhSyntheticKind::closed_plane, MhSyntheticKind::boxes_and_misses}) {
    Built b = build_both(make_synthetic_tile(kind, 256, 5));
    EXPECT_GT(b.stats.merges, 0u) << synthetic_kind_name(kind);
    EXPECT_LT(b.mmh_bytes.size(), b.mh_bytes.size()) << synthetic_kind_name(kind);
  }
}

// Coarse levels of a merged tree keep the bottom-up guarantee: each block's value is exact for at
// least one of its texels.
TEST(Mmh, CoarseLevelsExactSomewhereInEachBlock) {
  for (MhSyntheticKind kind : kKinds) {
    const uint32_t size = 64;
    const TileIntervals tile = make_synthetic_tile(kind, size, 3);
    Built b = build_both(tile);
    for (unsigned m = 0; m <= b.mmh.levels(); ++m) {
      const uint32_t block = size >> m;
      for (uint32_t by = 0; by < size; by += block)
        for (uint32_t bx = 0; bx < size; bx += block) {
          const float value = b.mmh.lookup(bx, by, m);
          bool exact = false;
          for (uint32_t v = by; v < by + block; ++v)
            for (uint32_t u = bx; u < bx + block; ++u) {
              ASSERT_EQ(b.mmh.lookup(u, v, m), value);
              exact |= tile.at(u, v).contains(value);
            }
          EXPECT_TRUE(exact) << synthetic_kind_name(kind) << " level " << m;
        }
    }
  }
}

// With 1- and 2-bit hashes nearly every bucket mixes topologies: the full comparison must reject
// them and the result stays exact.
TEST(Mmh, ForcedHashCollisionsStayExact) {
  for (unsigned bits : {1u, 2u, 4u}) {
    for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::steps,
                                 MhSyntheticKind::boxes_and_misses}) {
      const TileIntervals tile = make_synthetic_tile(kind, 128, bits);
      MmhMergeOptions options;
      options.hash_bits = bits;
      Built b = build_both(tile, options);
      EXPECT_GT(b.stats.topology_mismatches, 0u) << bits << " " << synthetic_kind_name(kind);
      Status s = verify_lossless(tile, b.mmh);
      EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
    }
  }
}

TEST(Mmh, TestBoundLimitsWork) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::steps, 256, 8);
  MmhMergeOptions one;
  one.max_tests_per_block = 1;
  Built few = build_both(tile, one);
  Built many = build_both(tile);
  EXPECT_LE(many.mmh_bytes.size(), few.mmh_bytes.size());
  EXPECT_TRUE(verify_lossless(tile, few.mmh).ok());
  MmhMergeOptions none;
  none.max_tests_per_block = 0;
  Built zero = build_both(tile, none);
  EXPECT_EQ(zero.stats.merges, 0u);
  EXPECT_EQ(zero.mmh_bytes, zero.mh_bytes);
}

TEST(Mmh, RejectsSharedInputAndBadOptions) {
  auto tree = build_mh(make_synthetic_tile(MhSyntheticKind::steps, 64, 2));
  ASSERT_TRUE(tree.ok());
  auto merged = merge_mmh(*tree);
  ASSERT_TRUE(merged.ok());
  ASSERT_LT(merged->block_count(), tree->block_count());
  EXPECT_FALSE(merge_mmh(*merged).ok());
  MmhMergeOptions bad;
  bad.hash_bits = 0;
  EXPECT_FALSE(merge_mmh(*tree, bad).ok());
}

// mmh_merge_finds_nothing's true must mean the merge finds nothing, so MMH is MH byte for byte.
void expect_proof_holds(const TileIntervals& tile, const char* what) {
  auto tree = build_mh(tile);
  ASSERT_TRUE(tree.ok());
  if (!mmh_merge_finds_nothing(*tree)) return;
  MmhMergeStats stats;
  auto merged = merge_mmh(*tree, {}, &stats);
  ASSERT_TRUE(merged.ok());
  EXPECT_EQ(stats.merges, 0u) << what;
  EXPECT_EQ(*encode_mh(*merged), *encode_mh(*tree)) << what;
}

// A copy of the 2x2 texels at (0, 0) over those at (u, v): two equal leaf blocks.
TileIntervals with_block_copied(TileIntervals tile, uint32_t u, uint32_t v) {
  for (uint32_t y = 0; y < 2; ++y)
    for (uint32_t x = 0; x < 2; ++x) tile.texels[size_t(v + y) * tile.size + u + x] = tile.at(x, y);
  return tile;
}

TEST(Mmh, NothingToMergeIsProvedOnlyWhereTheMergeFindsNothing) {
  // An open surface of distinct depths: every block point-like, no two alike.
  const TileIntervals plane = make_synthetic_tile(MhSyntheticKind::noisy_plane, 256, 5);
  auto tree = build_mh(plane);
  ASSERT_TRUE(tree.ok());
  ASSERT_TRUE(mmh_merge_finds_nothing(*tree));
  expect_proof_holds(plane, "noisy_plane");
  for (MhSyntheticKind kind : kKinds)
    for (uint32_t size : {2u, 16u, 128u}) expect_proof_holds(make_synthetic_tile(kind, size, 7), synthetic_kind_name(kind));

  // Two equal 2x2 blocks, neighbours or far apart in breadth-first order: a merge that tests every
  // representative shares them (the default's window of 1024 misses the far pair), and the check
  // must not claim otherwise.
  MmhMergeOptions unbounded;
  unbounded.max_tests_per_block = ~0u;
  for (auto [u, v] : {std::pair{2u, 0u}, std::pair{200u, 200u}}) {
    const TileIntervals twins = with_block_copied(plane, u, v);
    auto twin_tree = build_mh(twins);
    ASSERT_TRUE(twin_tree.ok());
    MmhMergeStats stats;
    ASSERT_TRUE(merge_mmh(*twin_tree, unbounded, &stats).ok());
    EXPECT_GT(stats.merges, 0u) << u << "," << v;
    EXPECT_FALSE(mmh_merge_finds_nothing(*twin_tree)) << u << "," << v;
  }

  // A wide interval fits a block of other values: twins but for one texel's upper bound merge, so
  // the check must not prove them apart by their values.
  TileIntervals widened = with_block_copied(plane, 2, 0);
  DepthInterval& wide = widened.texels[3];  // (3, 0): a value its leaf block keeps (not its first)
  wide.upper = std::nextafter(wide.upper, 1.0f);
  auto widened_tree = build_mh(widened);
  ASSERT_TRUE(widened_tree.ok());
  MmhMergeStats widened_stats;
  ASSERT_TRUE(merge_mmh(*widened_tree, {}, &widened_stats).ok());
  EXPECT_GT(widened_stats.merges, 0u);
  EXPECT_FALSE(mmh_merge_finds_nothing(*widened_tree));

  // Wide intervals (a closed solid) may fit blocks of other values: not provable.
  auto solid = build_mh(make_synthetic_tile(MhSyntheticKind::closed_plane, 64, 5));
  ASSERT_TRUE(solid.ok());
  EXPECT_FALSE(mmh_merge_finds_nothing(*solid));

  // An input that already shares blocks, or a malformed one, is never "nothing to merge".
  auto steps = build_mh(make_synthetic_tile(MhSyntheticKind::steps, 64, 2));
  ASSERT_TRUE(steps.ok());
  auto shared = merge_mmh(*steps);
  ASSERT_TRUE(shared.ok());
  ASSERT_LT(shared->block_count(), steps->block_count());
  EXPECT_FALSE(mmh_merge_finds_nothing(*shared));
  MhHierarchy broken = *tree;
  broken.child_block.back() = uint32_t(broken.block_count() + 5);
  EXPECT_FALSE(mmh_merge_finds_nothing(broken));
}

}  // namespace
}  // namespace shadowtiles
