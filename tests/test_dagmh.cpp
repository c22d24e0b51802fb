// DAG-MH encoding + decoding: exhaustive losslessness on synthetic tiles for every treelet height and
// several chunk sizes, coarse levels, PCF fast path = per-sample, forced hash collisions, MMH input,
// sizes against MH/MMH (printed).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <tuple>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/dagmh_decoder.hpp"
#include "tests/mh_reference_intervals.hpp"
#include "tests/parsed_payload.hpp"

namespace shadowtiles {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

constexpr auto& kKinds = kEveryMhSyntheticKind;

using Encoded = testing::ParsedPayload<DagMhTileView>;

Encoded encode_and_parse(const MhHierarchy& h, const DagMhOptions& o = {}) {
  return testing::parse_payload<DagMhTileView>(encode_dagmh(h, o));
}

uint64_t violations(const TileIntervals& tile, const DagMhTileView& view) {
  uint64_t bad = 0;
  for (uint32_t v = 0; v < tile.size; ++v)
    for (uint32_t u = 0; u < tile.size; ++u) {
      const float x = view.lookup(u, v);
      bad += !(std::isfinite(x) && tile.at(u, v).contains(x));
    }
  return bad;
}

using Param = std::tuple<MhSyntheticKind, uint32_t>;
class DagMhLossless : public ::testing::TestWithParam<Param> {};

TEST_P(DagMhLossless, EveryTexelInsideItsIntervalForEveryParameter) {
  const auto [kind, size] = GetParam();
  const TileIntervals tile = make_synthetic_tile(kind, size, 4321 + size);
  auto tree = build_mh(tile);
  ASSERT_TRUE(tree.ok());
  for (unsigned height = 2; height <= 5; ++height)
    for (unsigned chunk : {16u, 32u, 64u, 128u}) {
      if (size >= 512 && chunk != 32 && height != 4) continue;  // the full grid at <= 128, a cross at 512
      DagMhOptions o;
      o.treelet_height = height;
      o.chunk_size = chunk;
      Encoded e = encode_and_parse(*tree, o);
      ASSERT_EQ(e.view.size(), size);
      EXPECT_EQ(violations(tile, e.view), 0u) << "height " << height << " chunk " << chunk;
    }
}

std::string param_name(const ::testing::TestParamInfo<Param>& info) {
  std::string name = synthetic_kind_name(std::get<0>(info.param));
  name += '_';
  name += std::to_string(std::get<1>(info.param));
  return name;
}

INSTANTIATE_TEST_SUITE_P(Synthetic, DagMhLossless,
                         ::testing::Combine(::testing::ValuesIn(kKinds),
                                            ::testing::Values(1u, 2u, 4u, 8u, 16u, 32u, 128u, 512u)),
                         param_name);

TEST(DagMh, CoarseLevelsInsideTheNodeIntervals) {
  for (MhSyntheticKind kind : kKinds)
    for (uint32_t size : {1u, 2u, 16u, 64u})
      for (unsigned height : {2u, 4u, 5u}) {
        const TileIntervals tile = make_synthetic_tile(kind, size, 77 + size);
        DagMhOptions o;
        o.treelet_height = height;
        Encoded e = encode_and_parse(*build_mh(tile), o);
        ASSERT_NO_FATAL_FAILURE(testing::expect_coarse_levels_inside_reference(
            tile, e.view, false,
            std::string(synthetic_kind_name(kind)) + " size " + std::to_string(size) + " height " +
                std::to_string(height)));
      }
}

TEST(DagMh, PcfEqualsPerSampleLookups) {
  std::mt19937 rng(5);
  for (MhSyntheticKind kind : kKinds)
    for (uint32_t size : {1u, 8u, 64u})
      for (unsigned height : {2u, 4u}) {
        const TileIntervals tile = make_synthetic_tile(kind, size, 3 + size);
        DagMhOptions o;
        o.treelet_height = height;
        Encoded e = encode_and_parse(*build_mh(tile), o);
        for (int trial = 0; trial < 300; ++trial) {
          const uint32_t kw = 1 + rng() % std::min<uint32_t>(size, 9), kh = 1 + rng() % std::min<uint32_t>(size, 9);
          const uint32_t u0 = rng() % (size - kw + 1), v0 = rng() % (size - kh + 1);
          const float depth = float(rng() % 1000) / 1000.0f, bias = trial % 2 ? 0.001f : 0.0f;
          uint32_t expected = 0;
          for (uint32_t v = v0; v < v0 + kh; ++v)
            for (uint32_t u = u0; u < u0 + kw; ++u) expected += depth <= e.view.lookup(u, v) + bias;
          ASSERT_EQ(e.view.pcf_lit_count(u0, v0, kw, kh, depth, bias), expected)
              << synthetic_kind_name(kind) << " " << size << " box " << u0 << "," << v0 << " " << kw << "x" << kh;
        }
        uint32_t whole = 0;
        for (uint32_t v = 0; v < size; ++v)
          for (uint32_t u = 0; u < size; ++u) whole += 0.5f <= e.view.lookup(u, v);
        EXPECT_EQ(e.view.pcf_lit_count(0, 0, size, size, 0.5f, 0.0f), whole);
      }
}

// With 1..3-bit hashes nearly every bucket mixes shapes: the full key comparison must keep them
// apart, so the payload is byte-identical to the 64-bit one.
TEST(DagMh, ForcedHashCollisionsStayExact) {
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::steps,
                               MhSyntheticKind::boxes_and_misses}) {
    const TileIntervals tile = make_synthetic_tile(kind, 128, 11);
    auto tree = build_mh(tile);
    ASSERT_TRUE(tree.ok());
    const auto reference = encode_dagmh(*tree);
    ASSERT_TRUE(reference.ok());
    for (unsigned bits : {1u, 2u, 3u}) {
      DagMhOptions o;
      o.hash_bits = bits;
      Encoded e = encode_and_parse(*tree, o);
      EXPECT_EQ(e.bytes, *reference) << bits;
      EXPECT_EQ(violations(tile, e.view), 0u);
    }
  }
}

TEST(DagMh, MmhInputIsExpandedAndExact) {
  for (MhSyntheticKind kind : kKinds) {
    const TileIntervals tile = make_synthetic_tile(kind, 128, 21);
    auto merged = merge_mmh(*build_mh(tile));
    ASSERT_TRUE(merged.ok());
    Encoded e = encode_and_parse(*merged);
    EXPECT_EQ(violations(tile, e.view), 0u) << synthetic_kind_name(kind);
  }
}

TEST(DagMh, RejectsBadOptions) {
  auto tree = build_mh(make_synthetic_tile(MhSyntheticKind::steps, 16, 2));
  for (DagMhOptions o : {DagMhOptions{1, 32, 64}, DagMhOptions{6, 32, 64}, DagMhOptions{4, 0, 64},
                         DagMhOptions{4, 2000, 64}, DagMhOptions{4, 32, 0}})
    EXPECT_FALSE(encode_dagmh(*tree, o).ok());
}

// Sizes against MH and MMH on the synthetic tiles (printed), and the stats breakdown adds up.
TEST(DagMh, SizesAgainstMhAndMmh) {
  for (uint32_t size : {512u, 2048u}) {
    for (MhSyntheticKind kind : kKinds) {
      const TileIntervals tile = make_synthetic_tile(kind, size, 9);
      auto tree = build_mh(tile);
      auto merged = merge_mmh(*tree);
      const size_t mh = encode_mh(*tree)->size(), mmh = encode_mh(*merged)->size();
      Encoded e = encode_and_parse(*tree);
      const DagMhStats& s = e.view.stats();
      EXPECT_EQ(s.header_bytes + s.dag_bytes + s.treelet_bytes + s.chunk_table_bytes + s.chunk_header_bytes +
                    s.multiplier_bytes + s.raw_value_bytes,
                s.payload_bytes);
      EXPECT_EQ(s.representative_values + s.quantized_values + s.raw_values, s.values);
      std::printf("%5u %-17s MH %9zu  MMH %9zu  DAG-MH %9zu  DAG-MH/MMH %.3f  DAG-MH/MH %.3f | dag %llu (%llu nodes) "
                  "treelets %llu (%llu) chunk tbl %llu hdr %llu mult %llu raw %llu | values %llu rep %llu q %llu raw %llu\n",
                  size, synthetic_kind_name(kind), mh, mmh, e.bytes.size(), double(e.bytes.size()) / double(mmh),
                  double(e.bytes.size()) / double(mh), (unsigned long long)s.dag_bytes, (unsigned long long)s.dag_nodes,
                  (unsigned long long)s.treelet_bytes, (unsigned long long)s.treelets,
                  (unsigned long long)s.chunk_table_bytes, (unsigned long long)s.chunk_header_bytes,
                  (unsigned long long)s.multiplier_bytes, (unsigned long long)s.raw_value_bytes,
                  (unsigned long long)s.values, (unsigned long long)s.representative_values,
                  (unsigned long long)s.quantized_values, (unsigned long long)s.raw_values);
      // Smaller than MH wherever there is structure. Against MMH it wins on noisy and random tiles;
      // on the synthetic steps/boxes tiles (few values, MMH merges values too) it is still larger
      // (about 1.3x): printed above, to be measured on real scenes.
      if (kind != MhSyntheticKind::all_miss) {
        EXPECT_LT(e.bytes.size(), mh) << synthetic_kind_name(kind) << " " << size;
      }
      if (kind == MhSyntheticKind::random_intervals || kind == MhSyntheticKind::noisy_plane ||
          kind == MhSyntheticKind::closed_plane) {
        EXPECT_LT(e.bytes.size(), mmh) << synthetic_kind_name(kind) << " " << size;
      }
      if (size == 2048) {
        EXPECT_EQ(violations(tile, e.view), 0u);
      }
    }
  }
}

TEST(DagMh, ParameterStudyCoversTheGrid) {
  auto tree = build_mh(make_synthetic_tile(MhSyntheticKind::steps, 256, 3));
  auto study = dagmh_parameter_study(*tree);
  ASSERT_TRUE(study.ok());
  ASSERT_EQ(study->size(), 16u);
  for (const auto& p : *study) {
    std::printf("treelet height %u chunk %3u: %llu bytes\n", p.treelet_height, p.chunk_size,
                (unsigned long long)p.bytes);
  }
}

}  // namespace
}  // namespace shadowtiles
