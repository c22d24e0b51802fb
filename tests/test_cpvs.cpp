// CPVS encoder + decoder on synthetic tiles: every voxel (u, v, step) of the tile answers as the
// interval rule demands wherever the rule is not free (exhaustive), through lit_at_step and through
// lit() at every step's centre; PCF popcounts equal per-texel counting; the first shadowed step
// agrees with point lookups; a point query's sample() answers as lit() with a value the comparison
// `threshold <= value` agrees with; identical subtrees merge, and a 1-bit hash changes nothing (the key,
// not the hash, decides); both leaf layouts.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <random>

#include "builder/cpvs_encoder.hpp"
#include "codec/cpvs_decoder.hpp"
#include "codec/cpvs_tile_view.hpp"
#include "store/method.hpp"

namespace shadowtiles {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
using cpvs::LeafLayout;

// A mix of what real tiles hold: misses, open surfaces (lower == upper), closed objects (a free
// range inside), a sloped plane and steps, all at random depths.
TileIntervals mixed_tile(uint32_t size, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  TileIntervals tile{size, std::vector<DepthInterval>(size_t(size) * size)};
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      DepthInterval& t = tile.at(u, v);
      float plane = 0.2f + 0.5f * float(u + 2 * v) / float(3 * size);
      if (u < size / 4) {
        t = {1.0f, kInf};  // miss
      } else if (v < size / 3) {
        t = {plane, plane};  // open sloped surface
      } else if (u < size / 2) {
        float box = (u / 4 + v / 4) % 2 ? 0.35f : 0.6f;  // steps, closed
        t = {box, box + 0.2f};
      } else {
        float lower = unit(rng) * 0.9f;
        t = {lower, unit(rng) < 0.5f ? lower : lower + unit(rng) * 0.1f};
      }
    }
  return tile;
}

std::shared_ptr<const DecodedTile> decode(const std::vector<uint8_t>& payload) {
  auto tile = decode_cpvs_tile(payload);
  EXPECT_TRUE(tile.ok()) << tile.error().message;
  return tile.ok() ? *tile : nullptr;
}

CpvsTileView parse_view(const std::vector<uint8_t>& payload) {
  auto view = CpvsTileView::parse(payload);
  EXPECT_TRUE(view.ok()) << view.error().message;
  return view.ok() ? *view : CpvsTileView{};
}

// Exhaustive over every voxel: lit below lit_end, shadowed from shadow_begin on. Lookups start at
// the skip table's level (*skip_level), so every voxel is also checked against a view without one.
void expect_rule_holds(const TileIntervals& tile, uint32_t map_resolution, LeafLayout layout,
                       unsigned* skip_level = nullptr) {
  CpvsBuildOptions options;
  options.layout = layout;
  auto payload = encode_cpvs_tile(tile, map_resolution, options);
  ASSERT_TRUE(payload.ok()) << payload.error().message;
  CpvsTileView view = parse_view(*payload);
  auto decoded = decode(*payload);
  ASSERT_TRUE(decoded);
  if (skip_level) *skip_level = view.skip_level();
  auto from_root = CpvsTileView::parse(*payload, CpvsParseOptions{.max_skip_level = 0});
  ASSERT_TRUE(from_root.ok());
  ASSERT_EQ(from_root->skip_level(), 0u);
  const uint32_t n = cpvs::depth_steps_for(map_resolution, tile.size);
  ASSERT_EQ(view.depth_steps(), n);
  ASSERT_EQ(view.size(), tile.size);
  uint64_t checked = 0, free_steps = 0;
  for (uint32_t v = 0; v < tile.size; ++v)
    for (uint32_t u = 0; u < tile.size; ++u) {
      const DepthInterval& t = tile.at(u, v);
      cpvs::StepBounds b = cpvs::step_bounds(t.lower, t.upper, n);
      uint32_t first_shadow = n;
      for (uint32_t z = 0; z < n; ++z) {
        bool lit = view.lit_at_step(u, v, z);
        if (!lit && first_shadow == n) first_shadow = z;
        float centre = (float(z) + 0.5f) / float(n);
        ASSERT_EQ(decoded->lit(u, v, centre), lit) << "lit() quantises like lit_at_step";
        ASSERT_EQ(from_root->lit_at_step(u, v, z), lit) << u << "," << v << " step " << z;
        ASSERT_EQ(view.lit_count(u, v, 1, 1, centre), lit ? 1u : 0u) << u << "," << v << " step " << z;
        if (u + 2 <= tile.size && v + 2 <= tile.size) {
          ASSERT_EQ(view.lit_count(u, v, 2, 2, centre), from_root->lit_count(u, v, 2, 2, centre)) << u << "," << v;
        }
        // A point query's sample: lit() in one descent, with a value that the comparison agrees with.
        for (float t : {float(z) / float(n), centre, std::nextafter(float(z + 1) / float(n), 0.0f)}) {
          const DecodedTile::Sample sample = decoded->sample(u, v, t);
          ASSERT_EQ(sample.lit, decoded->lit(u, v, t)) << u << "," << v << " t " << t;
          ASSERT_EQ(t <= sample.value, sample.lit) << u << "," << v << " t " << t << " value " << sample.value;
        }
        if (z < b.lit_end) {
          ASSERT_TRUE(lit) << u << "," << v << " step " << z;
        } else if (z >= b.shadow_begin) {
          ASSERT_FALSE(lit) << u << "," << v << " step " << z;
        } else {
          ++free_steps;
        }
        ++checked;
      }
      ASSERT_EQ(view.first_shadowed_step(u, v), first_shadow);
      // The interval's consequence one and a half steps away from each bound.
      ASSERT_TRUE(decoded->lit(u, v, t.lower - 1.5f / float(n)));
      if (std::isfinite(t.upper) && t.upper + 1.5f / float(n) < 1.0f) {
        ASSERT_FALSE(decoded->lit(u, v, t.upper + 1.5f / float(n)));
      }
      ASSERT_TRUE(decoded->lit(u, v, -0.25f)) << "in front of the near plane";
    }
  EXPECT_EQ(checked, uint64_t(tile.size) * tile.size * n);
  EXPECT_GT(free_steps, 0u) << "the tile exercises free voxels";
}

TEST(Cpvs, EveryVoxelFollowsTheIntervalRuleSlab8) {
  unsigned skip = 0;
  expect_rule_holds(mixed_tile(32, 1), 64, LeafLayout::slab8, &skip);
  EXPECT_GT(skip, 0u) << "point lookups start from the skip table";
}
TEST(Cpvs, EveryVoxelFollowsTheIntervalRuleCube4) {
  unsigned skip = 0;
  expect_rule_holds(mixed_tile(32, 2), 64, LeafLayout::cube4, &skip);
  EXPECT_GT(skip, 0u);
}
TEST(Cpvs, SkipTableCellsSplitTheTileInUAndV) {
  // Tile as wide as the depth cube: level-2 cells are a quarter of the tile on each axis, so a
  // lookup's cell depends on u, v and the step.
  for (LeafLayout layout : {LeafLayout::slab8, LeafLayout::cube4}) {
    unsigned skip = 0;
    expect_rule_holds(mixed_tile(64, 9), 64, layout, &skip);
    EXPECT_GE(skip, 2u);
  }
}
TEST(Cpvs, TileNarrowerThanTheDepthCube) {
  // N = 256 steps, the tile is 16 texels wide: the cube's other texels are free and never queried.
  // The skip table's cells then span the whole tile in u and v at the top levels.
  unsigned skip = 0;
  expect_rule_holds(mixed_tile(16, 3), 256, LeafLayout::slab8, &skip);
  EXPECT_GT(skip, 0u);
  expect_rule_holds(mixed_tile(16, 4), 256, LeafLayout::cube4);
}
TEST(Cpvs, SkipTableStaysWithinAnEighthOfThePayload) {
  for (uint32_t size : {32u, 64u, 128u}) {
    auto payload = encode_cpvs_tile(mixed_tile(size, 7), 4 * size);
    ASSERT_TRUE(payload.ok());
    CpvsTileView view = parse_view(*payload);
    EXPECT_LE(view.derived_bytes() * 8, payload->size()) << size;
    EXPECT_GT(view.skip_level(), 0u) << size;
  }
}
TEST(Cpvs, TinyTilesUseTheMinimumCube) {
  expect_rule_holds(mixed_tile(4, 5), 4, LeafLayout::slab8);
  expect_rule_holds(mixed_tile(8, 6), 8, LeafLayout::cube4);
}

TEST(Cpvs, ConstantTilesHaveNoNodes) {
  TileIntervals misses{16, std::vector<DepthInterval>(256)};
  auto payload = encode_cpvs_tile(misses, 64);
  ASSERT_TRUE(payload.ok());
  CpvsTileView view = parse_view(*payload);
  EXPECT_EQ(view.stats().nodes, 0u);
  EXPECT_EQ(view.stats().leaves, 0u);
  EXPECT_TRUE(view.lit_at_step(3, 3, 63));
  EXPECT_EQ(view.first_shadowed_step(3, 3), 64u);
}

TEST(Cpvs, PcfCountsEqualPerTexelCounting) {
  TileIntervals tile = mixed_tile(64, 7);
  for (LeafLayout layout : {LeafLayout::slab8, LeafLayout::cube4}) {
    CpvsBuildOptions options;
    options.layout = layout;
    auto payload = encode_cpvs_tile(tile, 128, options);
    ASSERT_TRUE(payload.ok());
    auto decoded = decode(*payload);
    ASSERT_TRUE(decoded);
    std::mt19937 rng(11);
    for (int trial = 0; trial < 3000; ++trial) {
      uint32_t kw = 1 + rng() % 13, kh = 1 + rng() % 13;
      uint32_t u0 = rng() % (64 - kw + 1), v0 = rng() % (64 - kh + 1);
      float threshold = std::uniform_real_distribution<float>(-0.05f, 1.05f)(rng);
      uint32_t expected = 0;
      for (uint32_t v = v0; v < v0 + kh; ++v)
        for (uint32_t u = u0; u < u0 + kw; ++u) expected += decoded->lit(u, v, threshold);
      ASSERT_EQ(decoded->lit_count(u0, v0, kw, kh, threshold), expected)
          << "layout " << int(layout) << " box " << u0 << "," << v0 << " " << kw << "x" << kh;
    }
  }
}

TEST(Cpvs, IdenticalSubtreesMerge) {
  // A periodic pattern (an 8x8 motif of two depths) repeated over the tile: the DAG keeps one copy.
  TileIntervals tile{128, std::vector<DepthInterval>(128 * 128)};
  for (uint32_t v = 0; v < 128; ++v)
    for (uint32_t u = 0; u < 128; ++u) {
      float d = ((u % 8) + (v % 8)) % 3 == 0 ? 0.3f : 0.55f;
      tile.at(u, v) = {d, d};
    }
  // Distinct masks the motif allows: slabs, one 8x8 pattern (+ its boundary step); cubes, four 4x4
  // quadrants, each in the middle of the run and at the entry step of each depth (lit: not free).
  for (auto [layout, most_leaves] : {std::pair{LeafLayout::slab8, 4u}, std::pair{LeafLayout::cube4, 12u}}) {
    CpvsBuildOptions options;
    options.layout = layout;
    auto dag = build_cpvs_dag(tile, 256, options);
    ASSERT_TRUE(dag.ok());
    uint64_t unique = 0;
    for (const auto& level : dag->levels) unique += level.size();
    EXPECT_GT(dag->stats.nodes_visited, 10 * unique) << "repeated subtrees are stored once";
    EXPECT_LE(dag->leaves.size(), most_leaves) << "layout " << int(layout);
  }
}

TEST(Cpvs, MergingIsDecidedByFullComparisonNotByTheHash) {
  // With a 1-bit hash every node collides with half of all others; only the key comparison can tell
  // them apart. The payload must be byte-identical to the full-hash one, and must decode right.
  TileIntervals tile = mixed_tile(32, 9);
  for (LeafLayout layout : {LeafLayout::slab8, LeafLayout::cube4}) {
    CpvsBuildOptions full, tiny;
    full.layout = tiny.layout = layout;
    tiny.hash_bits = 1;
    auto a = encode_cpvs_tile(tile, 64, full);
    auto b = encode_cpvs_tile(tile, 64, tiny);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(*a, *b);
  }
  expect_rule_holds(tile, 64, LeafLayout::slab8);
}

// The inline ref counting equals std::popcount for every 16-bit code word and every child.
TEST(Cpvs, RefRankCountsLikePopcountForEveryCodeWord) {
  for (uint32_t codes = 0; codes <= 0xFFFFu; ++codes) {
    const uint16_t refs = cpvs::ref_bits(uint16_t(codes));
    ASSERT_EQ(cpvs::ref_count(uint16_t(codes)), unsigned(std::popcount(refs))) << codes;
    for (unsigned child = 0; child < 8; ++child)
      ASSERT_EQ(cpvs::ref_rank(uint16_t(codes), child), unsigned(std::popcount(unsigned(refs) & ((1u << (2 * child)) - 1u))))
          << codes << " child " << child;
  }
}

TEST(Cpvs, GoesThroughTheGenericDecoder) {
  auto payload = encode_cpvs_tile(mixed_tile(16, 12), 32);
  ASSERT_TRUE(payload.ok());
  auto tile = decode_tile(store::Method::cpvs, *payload);
  ASSERT_TRUE(tile.ok()) << tile.error().message;
  EXPECT_EQ((*tile)->size(), 16u);
  auto parts = (*tile)->size_breakdown();
  uint64_t sum = 0;
  for (const auto& part : parts) sum += part.bytes;
  EXPECT_EQ(sum, payload->size()) << "the breakdown covers the whole payload";
  EXPECT_GE((*tile)->memory_bytes(), payload->size());
}

TEST(Cpvs, RejectsMalformedIntervals) {
  TileIntervals tile = mixed_tile(16, 13);
  tile.at(5, 5) = {0.5f, 0.4f};
  EXPECT_EQ(encode_cpvs_tile(tile, 64).error().code, ErrorCode::invalid_input);
  tile.at(5, 5) = {std::nanf(""), 1.0f};
  EXPECT_EQ(encode_cpvs_tile(tile, 64).error().code, ErrorCode::invalid_input);
  EXPECT_EQ(encode_cpvs_tile(mixed_tile(16, 14), 8).error().code, ErrorCode::invalid_input) << "map < tile";
  TileIntervals odd{12, std::vector<DepthInterval>(144)};
  EXPECT_EQ(encode_cpvs_tile(odd, 64).error().code, ErrorCode::invalid_input);
}

}  // namespace
}  // namespace shadowtiles
