// MH construction + encoding + decoding: exhaustive losslessness on synthetic tiles, coarse-level
// guarantees, input validation, skip list.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <tuple>

#include "builder/mh_builder.hpp"
#include "builder/mh_dense_levels.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mmh_merger.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mh_verify.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/mh_format.hpp"
#include "tests/mh_reference_intervals.hpp"
#include "tests/parsed_payload.hpp"

namespace shadowtiles {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

constexpr auto& kKinds = kEveryMhSyntheticKind;

using Encoded = testing::ParsedPayload<MhTileView>;

Encoded encode_and_parse(const TileIntervals& tile, MhConstruction construction, MhEncodeOptions encode = {}) {
  auto h = build_mh(tile, {construction});
  EXPECT_TRUE(h.ok()) << (h.ok() ? "" : h.error().message);
  if (!h.ok()) return {};
  return testing::parse_payload<MhTileView>(encode_mh(*h, encode));
}

using testing::reference_intervals;

using Param = std::tuple<MhConstruction, MhSyntheticKind, uint32_t>;
class MhLossless : public ::testing::TestWithParam<Param> {};

TEST_P(MhLossless, EveryTexelInsideItsInterval) {
  const auto [construction, kind, size] = GetParam();
  const TileIntervals tile = make_synthetic_tile(kind, size, 1234 + size);
  Encoded e = encode_and_parse(tile, construction);
  ASSERT_EQ(e.view.size(), size);
  MhVerifyReport report;
  Status s = verify_lossless(tile, e.view, &report);
  EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
  EXPECT_EQ(report.texels, uint64_t(size) * size);
  EXPECT_EQ(report.violations, 0u);
  for (const float x : {e.view.lookup(0, 0), e.view.lookup(size - 1, size - 1)}) EXPECT_TRUE(std::isfinite(x));
}

std::string param_name(const ::testing::TestParamInfo<Param>& info) {
  return std::string(std::get<0>(info.param) == MhConstruction::bottom_up ? "bottom_up" : "top_down") + "_" +
         synthetic_kind_name(std::get<1>(info.param)) + "_" + std::to_string(std::get<2>(info.param));
}

INSTANTIATE_TEST_SUITE_P(Synthetic, MhLossless,
                         ::testing::Combine(::testing::Values(MhConstruction::bottom_up, MhConstruction::top_down),
                                            ::testing::ValuesIn(kKinds),
                                            ::testing::Values(1u, 2u, 4u, 8u, 32u, 128u, 512u)),
                         param_name);

// Bottom-up coarse levels: at level m every texel of a level-m block reads the same value, that value
// lies inside the block's reference interval, and it is exact for at least one texel of the block.
TEST(MhCoarseLevels, EachLevelIsACompleteMapExactSomewhereInEachBlock) {
  for (MhSyntheticKind kind : kKinds) {
    for (uint32_t size : {1u, 2u, 16u, 64u}) {
      const TileIntervals tile = make_synthetic_tile(kind, size, 77 + size);
      Encoded e = encode_and_parse(tile, MhConstruction::bottom_up);
      ASSERT_NO_FATAL_FAILURE(testing::expect_coarse_levels_inside_reference(
          tile, e.view, true, std::string(synthetic_kind_name(kind)) + " size " + std::to_string(size)));
    }
  }
}

TEST(MhBuild, RejectsMalformedInput) {
  TileIntervals tile{3, std::vector<DepthInterval>(9)};
  EXPECT_FALSE(build_mh(tile).ok());
  tile = make_synthetic_tile(MhSyntheticKind::noisy_plane, 4, 1);
  tile.texels[5].lower = std::nanf("");
  EXPECT_FALSE(build_mh(tile).ok());
  tile.texels[5] = {0.5f, 0.4f};
  EXPECT_FALSE(build_mh(tile).ok());
  tile.texels[5] = {-kInf, 0.4f};
  EXPECT_FALSE(build_mh(tile).ok());
  // A 1x1 tile (no levels below the root) is tested as well.
  TileIntervals one{1, {{std::nanf(""), 1.0f}}};
  EXPECT_FALSE(build_mh(one).ok());
  one.texels[0] = {0.5f, 0.6f};
  EXPECT_TRUE(build_mh(one).ok());
  one.entry_lower = {std::nanf("")};
  EXPECT_FALSE(build_mh(one).ok());
  tile.texels.pop_back();
  auto r = build_mh(tile);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::invalid_input);
}

// A tile whose entry-rule bounds are not yet applied builds the MH of the applied tile, byte for
// byte, without the caller's copy (the build path since the encoders stopped copying the tile).
TEST(MhBuild, UnappliedEntryBoundsBuildTheAppliedTilesTree) {
  for (MhConstruction construction : {MhConstruction::bottom_up, MhConstruction::top_down}) {
    for (MhSyntheticKind kind : kKinds) {
      for (uint32_t size : {1u, 2u, 64u}) {
        TileIntervals unapplied = make_synthetic_tile(kind, size, 91 + size);
        unapplied.entry_lower.assign(unapplied.texels.size(), 1.0f);
        uint64_t state = 12345 + size;
        size_t lowered = 0;
        for (size_t i = 0; i < unapplied.texels.size(); ++i) {
          state = state * 6364136223846793005ull + 1442695040888963407ull;
          const float lower = unapplied.texels[i].lower;
          if (lower >= 1.0f || (state >> 33) % 3 == 0) continue;
          unapplied.entry_lower[i] = lower - 0.01f * float((state >> 40) % 5 + 1);  // as the rule: below the first hit
          ++lowered;
        }
        TileIntervals applied = unapplied;
        apply_entry_rule(applied);
        const std::string what = std::string(synthetic_kind_name(kind)) + " size " + std::to_string(size);
        auto from_unapplied = build_mh(unapplied, {construction});
        auto from_applied = build_mh(applied, {construction});
        ASSERT_TRUE(from_unapplied.ok() && from_applied.ok()) << what;
        EXPECT_EQ(encode_mh(*from_unapplied).value(), encode_mh(*from_applied).value()) << what;
        if (size == 64 && kind != MhSyntheticKind::all_miss) {  // the bounds did change the tree
          EXPECT_GT(lowered, 0u) << what;
          TileIntervals ignored = unapplied;
          ignored.entry_lower.clear();
          EXPECT_NE(encode_mh(*build_mh(ignored, {construction})).value(), encode_mh(*from_applied).value()) << what;
        }
      }
    }
  }
}

TEST(MhBuild, RejectsEntryBoundsThatAreNotOneFiniteValuePerTexel) {
  TileIntervals tile = make_synthetic_tile(MhSyntheticKind::noisy_plane, 4, 1);
  tile.entry_lower.assign(15, 0.5f);
  EXPECT_FALSE(build_mh(tile).ok());
  tile.entry_lower.assign(16, 0.5f);
  EXPECT_TRUE(build_mh(tile).ok());
  tile.entry_lower[3] = std::nanf("");
  EXPECT_FALSE(build_mh(tile).ok());
}

TEST(MhBuild, AllMissIsARootLeafWithAFiniteValue) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::all_miss, 256, 1);
  Encoded e = encode_and_parse(tile, MhConstruction::bottom_up);
  EXPECT_EQ(e.view.stats().nodes(), 1u);
  EXPECT_EQ(e.bytes.size(), e.view.stats().header_bytes);
  EXPECT_EQ(e.view.lookup(17, 200), 1.0f);
}

// The bottom-up rule written out plainly: per parent, the lower covered by the most children (ties
// to the first) and the children it covers, level by level in Morton order, with no shortcut.
// build_mh's bottom-up builder skips the search for four equal children and for four that share a
// depth; it must give these bytes.
MhHierarchy bottom_up_by_search(const TileIntervals& tile) {
  const unsigned levels = unsigned(std::countr_zero(tile.size));
  MhDenseLevels dense;
  dense.size = tile.size;
  dense.levels = levels;
  dense.masks.resize(levels);
  dense.valued.resize(levels + 1);
  std::vector<DepthInterval> child(tile.texels.size());
  for (size_t m = 0; m < child.size(); ++m) child[m] = tile.texels[size_t(morton_y(m)) * tile.size + morton_x(m)];
  for (unsigned l = levels; l-- > 0;) {
    const size_t n = size_t(1) << (2 * l);
    std::vector<DepthInterval> parent(n);
    dense.masks[l].assign(n, 0);
    for (size_t p = 0; p < n; ++p) {
      const DepthInterval* c = &child[4 * p];
      unsigned best = 0, best_count = 0;
      for (unsigned i = 0; i < 4; ++i) {
        unsigned count = 0;
        for (unsigned j = 0; j < 4; ++j) count += c[j].lower <= c[i].lower && c[i].lower <= c[j].upper;
        if (count > best_count) best = i, best_count = count;
      }
      const float candidate = c[best].lower;
      DepthInterval interval{-kInf, kInf};
      uint8_t mask = 0;
      for (unsigned i = 0; i < 4; ++i) {
        unsigned code = 0;
        if (c[i].lower <= candidate && candidate <= c[i].upper) {
          interval.lower = std::max(interval.lower, c[i].lower);
          interval.upper = std::min(interval.upper, c[i].upper);
        } else {
          code = 1;
          dense.valued[l + 1].push_back(c[i]);
        }
        if (l + 1 < levels && dense.masks[l + 1][4 * p + i] != 0) code |= 2;
        mask |= uint8_t(code << (2 * i));
      }
      dense.masks[l][p] = mask;
      parent[p] = interval;
    }
    child = std::move(parent);
  }
  dense.valued[0] = {child[0]};
  return to_hierarchy(std::move(dense));
}

TEST(MhBuild, BottomUpShortcutsGiveTheSearchsBytes) {
  std::vector<std::pair<std::string, TileIntervals>> tiles;
  for (MhSyntheticKind kind : kKinds)
    for (uint32_t seed : {3u, 17u}) tiles.emplace_back(synthetic_kind_name(kind), make_synthetic_tile(kind, 64, seed));
  // Smooth slopes with room behind them (most 2x2 blocks share a depth), ties, zero widths and holes.
  for (uint32_t seed : {5u, 29u}) {
    TileIntervals slope;
    slope.size = 128;
    slope.texels.resize(size_t(128) * 128);
    uint64_t state = seed;
    auto next = [&] { return (state = state * 6364136223846793005ull + 1442695040888963407ull) >> 40; };
    for (uint32_t v = 0; v < 128; ++v)
      for (uint32_t u = 0; u < 128; ++u) {
        const float lower = 0.2f + 0.001f * float(u) + 0.0005f * float(v) + (next() % 7 == 0 ? 0.01f : 0.0f);
        const uint64_t pick = next() % 10;
        const float width = pick == 0 ? 0.0f : pick == 1 ? 0.0005f : 0.002f * float(next() % 20);
        slope.texels[size_t(v) * 128 + u] = next() % 50 == 0 ? DepthInterval{1.0f, 1.0f} : DepthInterval{lower, lower + width};
      }
    tiles.emplace_back("slope " + std::to_string(seed), std::move(slope));
  }
  // Signed zeros: the shortcut's folds must keep the zero the search keeps (the first of equal ones).
  // The payload's values are midpoints, which lose a zero's sign, so the root's bits are compared
  // too (the tile's root interval goes into its info record and the top levels).
  {
    TileIntervals zeros;
    zeros.size = 64;
    zeros.texels.resize(size_t(64) * 64);
    uint64_t state = 7;
    auto next = [&] { return (state = state * 6364136223846793005ull + 1442695040888963407ull) >> 40; };
    for (DepthInterval& t : zeros.texels) {
      // Mostly -0, +0 first: the search keeps the first zero of a tie, so the root's lower is +0.
      const float lower = &t == &zeros.texels[0] || next() % 4 == 0 ? 0.0f : -0.0f;
      const uint64_t pick = next() % 3;
      t = {lower, pick == 0 ? 0.0f : pick == 1 ? -0.0f : 0.001f * float(next() % 4)};
    }
    tiles.emplace_back("signed zeros", std::move(zeros));
  }
  for (auto& [name, tile] : tiles) {
    auto built = build_mh(tile, {MhConstruction::bottom_up});
    ASSERT_TRUE(built.ok()) << name;
    const MhHierarchy reference = bottom_up_by_search(tile);
    EXPECT_EQ(encode_mh(*built).value(), encode_mh(reference).value()) << name;
    EXPECT_EQ(std::bit_cast<uint32_t>(built->root.lower), std::bit_cast<uint32_t>(reference.root.lower)) << name;
    EXPECT_EQ(std::bit_cast<uint32_t>(built->root.upper), std::bit_cast<uint32_t>(reference.root.upper)) << name;
    // With entry-rule bounds, which the builder applies as it reads the texels.
    TileIntervals unapplied = tile;
    unapplied.entry_lower.resize(tile.texels.size());
    for (size_t i = 0; i < tile.texels.size(); ++i)
      unapplied.entry_lower[i] = i % 3 == 0 ? tile.texels[i].lower - 0.003f : 1.0f;
    TileIntervals applied = unapplied;
    apply_entry_rule(applied);
    auto built_unapplied = build_mh(unapplied, {MhConstruction::bottom_up});
    ASSERT_TRUE(built_unapplied.ok()) << name;
    EXPECT_EQ(encode_mh(*built_unapplied).value(), encode_mh(bottom_up_by_search(applied)).value()) << name;
  }
}

TEST(MhBuild, RootSummaryIsTheRootInterval) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::closed_plane, 64, 5);
  auto h = build_mh(tile);
  ASSERT_TRUE(h.ok());
  const auto ref = reference_intervals(tile);
  EXPECT_EQ(summarize(*h).root.lower, ref[0][0].lower);
  EXPECT_EQ(summarize(*h).root.upper, ref[0][0].upper);
}

// An embedded skip list is validated against the tree and gives identical lookups.
TEST(MhSkipList, EmbeddedEqualsDerived) {
  for (unsigned skip : {1u, 3u, 6u, 9u}) {
    const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::steps, 128, skip);
    Encoded plain = encode_and_parse(tile, MhConstruction::bottom_up);
    MhEncodeOptions options;
    options.embed_skip_list = true;
    options.skip_level = skip;
    Encoded with = encode_and_parse(tile, MhConstruction::bottom_up, options);
    EXPECT_EQ(with.view.stats().skip_level, std::min(skip, 7u));
    EXPECT_GT(with.bytes.size(), plain.bytes.size());
    for (uint32_t v = 0; v < 128; ++v)
      for (uint32_t u = 0; u < 128; ++u)
        for (unsigned m : {0u, 2u, 5u, 7u}) ASSERT_EQ(with.view.lookup(u, v, m), plain.view.lookup(u, v, m));
    // A parse without any skip list agrees too.
    MhParseOptions no_skip;
    no_skip.skip_level = 0;
    auto bare = MhTileView::parse(plain.bytes, no_skip);
    ASSERT_TRUE(bare.ok());
    for (uint32_t v = 0; v < 128; v += 3)
      for (uint32_t u = 0; u < 128; u += 5) ASSERT_EQ(bare->lookup(u, v), plain.view.lookup(u, v));
  }
}

// Without the skip list's choice given, the view takes the deepest level whose entries stay within a
// fifth of the payload: deep on a large full-depth tile, shallow on a small one, and the
// lookups equal a walk from the root.
TEST(MhSkipList, LevelChosenByPayloadSize) {
  struct Case {
    MhSyntheticKind kind;
    uint32_t size;
  };
  for (const Case c : {Case{MhSyntheticKind::noisy_plane, 1024}, Case{MhSyntheticKind::steps, 128},
                       Case{MhSyntheticKind::all_miss, 64}}) {
    const TileIntervals tile = make_synthetic_tile(c.kind, c.size, 7);
    Encoded e = encode_and_parse(tile, MhConstruction::bottom_up);
    const MhTileView& view = e.view;
    const unsigned S = view.skip_level();
    EXPECT_LE(view.derived_bytes() * 5, e.bytes.size()) << c.size;
    if (S > 0 && S < std::min(view.levels(), 10u)) {
      EXPECT_GT(view.derived_bytes() * 4 * 5, e.bytes.size()) << c.size << ": one level deeper would fit";
    }
    if (c.size == 1024) {
      EXPECT_GE(S, 7u) << "a large full-depth tile starts below the old fixed level 6";
    }
    if (c.kind == MhSyntheticKind::all_miss) {
      EXPECT_EQ(S, 0u) << "a root leaf needs no skip list";
    }
    MhParseOptions from_root;
    from_root.skip_level = 0;
    auto bare = MhTileView::parse(e.bytes, from_root);
    ASSERT_TRUE(bare.ok());
    EXPECT_EQ(bare->skip_level(), 0u);
    for (uint32_t v = 0; v < c.size; v += 7)
      for (uint32_t u = 0; u < c.size; u += 3)
        for (unsigned m : {0u, 3u, 8u, kMhAllLevels}) ASSERT_EQ(view.lookup(u, v, m), bare->lookup(u, v, m));
  }
}

// The encoder writes a tree's blocks in preorder: each block, then its children's subtrees in child
// order, so a walk's last levels lie within a few hundred bytes (one region per level before).
TEST(MhEncode, BlocksInPreorder) {
  namespace F = mh_format;
  for (const MhSyntheticKind kind : {MhSyntheticKind::noisy_plane, MhSyntheticKind::steps}) {
    const TileIntervals tile = make_synthetic_tile(kind, 256, 11);
    Encoded e = encode_and_parse(tile, MhConstruction::bottom_up);
    ASSERT_FALSE(e.bytes.empty());
    const uint8_t* head = e.bytes.data();
    const unsigned W = head[F::kOffOffsetWidth];
    ASSERT_EQ(head[F::kOffSkipLevel], 0u);
    uint32_t stream_bytes;
    std::memcpy(&stream_bytes, head + F::kOffStreamBytes, 4);
    const uint8_t* stream = head + F::kHeaderBytes;
    uint64_t next = 0;  // where the next block in preorder must start
    uint64_t blocks = 0;
    auto visit = [&](auto&& self, uint32_t offset, uint8_t mask) -> void {
      ASSERT_EQ(offset, next) << "block " << blocks;
      ++blocks;
      next += F::block_bytes(mask, W);
      for (unsigned r = 0; r < F::branch_children(mask); ++r) {
        const uint8_t* record = stream + offset + r * F::record_bytes(W);
        uint32_t child = 0;
        std::memcpy(&child, record + 1, W);
        self(self, child, record[0]);
      }
    };
    ASSERT_NE(head[F::kOffRootMask], 0u);
    visit(visit, 0, head[F::kOffRootMask]);
    EXPECT_EQ(next, stream_bytes);
    EXPECT_EQ(blocks, e.view.stats().blocks);
  }
}

TEST(MhEncode, ReferenceSizeCountsNodeTypes) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::steps, 64, 3);
  auto h = build_mh(tile);
  ASSERT_TRUE(h.ok());
  const MhNodeCounts c = count_nodes(*h);
  EXPECT_EQ(sbe16a_reference_bytes(*h), 8 * c.inner + 4 * (c.empty + c.leaves));
  Encoded e = encode_and_parse(tile, MhConstruction::bottom_up);
  EXPECT_EQ(e.view.stats().inner_nodes, c.inner);
  EXPECT_EQ(e.view.stats().empty_nodes, c.empty);
  EXPECT_EQ(e.view.stats().leaf_nodes, c.leaves);
  // A merged tree: the decoder's counts of its stream (shared blocks once) are the stored counts,
  // and expanding the sharing gives back the unmerged tree's size.
  MmhMergeStats stats;
  auto merged = merge_mmh(*h, {}, &stats);
  ASSERT_TRUE(merged.ok());
  ASSERT_GT(stats.merges, 0u);
  const MhNodeCounts m = count_nodes(*merged);
  auto view = testing::parse_payload<MhTileView>(encode_mh(*merged));
  EXPECT_EQ(view.view.stats().blocks, m.blocks);
  EXPECT_EQ(view.view.stats().inner_nodes, m.inner);
  EXPECT_EQ(view.view.stats().empty_nodes, m.empty);
  EXPECT_EQ(view.view.stats().leaf_nodes, m.leaves);
  EXPECT_LT(m.blocks, c.blocks);
  EXPECT_EQ(c.tree_nodes, c.inner + c.empty + c.leaves);  // unshared: every node stored once
  EXPECT_EQ(m.tree_nodes, c.tree_nodes);
  EXPECT_EQ(sbe16a_reference_bytes(*merged), 8 * m.inner + 4 * (m.empty + m.leaves));
}

}  // namespace
}  // namespace shadowtiles
