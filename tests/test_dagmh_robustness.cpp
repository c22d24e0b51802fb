// The DAG-MH decoder against hostile payloads at several treelet heights, chunk sizes and skip
// levels: every truncation, every single bit flip, random multi-byte corruption, hostile header
// fields, wrong magic and version. Each must give an
// error or a view whose lookups stay in bounds and finite (run under ASan: -DSHADOWTILES_SANITIZE=ON).
// Every trial copies the bytes into an exact-size buffer so a read past the end is caught.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_synthetic.hpp"
#include "codec/dagmh_decoder.hpp"
#include "codec/dagmh_format.hpp"
#include "tests/payload_attacks.hpp"

namespace shadowtiles {
namespace {

namespace F = dagmh_format;

// Treelet heights 2 and 4 (chunks of 16 and 32 values).
testing::Payloads encode_heights(const TileIntervals& tile) {
  auto tree = build_mh(tile);
  testing::Payloads out;
  for (unsigned height : {2u, 4u}) {
    DagMhOptions o;
    o.treelet_height = height;
    o.chunk_size = height == 2 ? 16 : 32;
    out.push_back(*encode_dagmh(*tree, o));
  }
  return out;
}

testing::Payloads sample_payloads() {
  return testing::encode_sample_tiles({MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                                       MhSyntheticKind::closed_plane, MhSyntheticKind::all_miss},
                                      encode_heights);
}

// Accepted only when every skip level parses it.
bool try_parse(const std::vector<uint8_t>& bytes) {
  for (unsigned skip : {6u, 2u, 0u}) {
    DagMhParseOptions o;
    o.skip_level = skip;
    if (!testing::parse_exact(
            bytes, [&](std::span<const uint8_t> exact) { return DagMhTileView::parse(exact, o); },
            [](const DagMhTileView& view) { testing::exercise_hierarchy_view(view, kDagMhAllLevels); }))
      return false;
  }
  return true;
}

TEST(DagMhRobustness, EveryTruncationIsAnError) {
  for (const auto& p : sample_payloads())
    for (size_t len = 0; len < p.size(); ++len)
      EXPECT_FALSE(try_parse(std::vector<uint8_t>(p.begin(), p.begin() + len))) << "length " << len;
}

TEST(DagMhRobustness, EverySingleBitFlipIsSafe) {
  // Value bits (representatives, raw floats, multipliers) are legitimately accepted.
  testing::expect_every_bit_flip_safe(sample_payloads(), try_parse);
}

TEST(DagMhRobustness, RandomMultiByteCorruptionIsSafe) {
  testing::random_multi_byte_corruption(sample_payloads(), try_parse, 20000, 5);
}

TEST(DagMhRobustness, HostileHeaderFields) {
  testing::hostile_header_fields(sample_payloads(),
                                 {F::kOffSize, F::kOffRootRef, F::kOffDagBytes, F::kOffTreeletCount, F::kOffValueCount,
                                  F::kOffChunkBytes},
                                 {F::kOffLevels, F::kOffTreeletHeight, F::kOffRefWidth, F::kOffCountWidth,
                                  F::kOffChunkOffsetWidth, F::kOffRootKind, F::kOffChunkSize, F::kOffChunkSize + 1},
                                 try_parse);
}

TEST(DagMhRobustness, MagicAndVersion) {
  testing::expect_magic_and_version_checked(sample_payloads()[3], F::kOffVersion, F::kFormatVersion,
                                            [](const std::vector<uint8_t>& q) { return DagMhTileView::parse(q); });
}

}  // namespace
}  // namespace shadowtiles
