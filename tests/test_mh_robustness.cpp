// The MH decoder against hostile payloads, skip-list payloads (top trees) included: bit flips,
// random corruption, hostile header fields, wrong magic and version. Each must give an error or a view whose lookups stay in bounds (run under ASan:
// -DSHADOWTILES_SANITIZE=ON). Every trial copies the bytes into an exact-size buffer so a read past
// the end is caught.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/mh_format.hpp"
#include "tests/payload_attacks.hpp"

namespace shadowtiles {
namespace {

// MH, MMH and MMH with a skip list.
testing::Payloads encode_all(const TileIntervals& tile) {
  auto tree = build_mh(tile);
  auto merged = merge_mmh(*tree);
  MhEncodeOptions skip;
  skip.embed_skip_list = true;
  skip.skip_level = 2;
  return {*encode_mh(*tree), *encode_mh(*merged), *encode_mh(*merged, skip)};
}

testing::Payloads sample_payloads() {
  return testing::encode_sample_tiles({MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                                       MhSyntheticKind::boxes_and_misses, MhSyntheticKind::all_miss},
                                      encode_all);
}

bool try_parse(const std::vector<uint8_t>& bytes) {
  return testing::parse_exact(
      bytes, [](std::span<const uint8_t> exact) { return MhTileView::parse(exact); },
      [](const MhTileView& view) { testing::exercise_hierarchy_view(view, kMhAllLevels); });
}

TEST(MhRobustness, EverySingleBitFlipIsSafe) {
  // Flipped value bits are legitimately accepted (a different finite value); structure flips are not.
  testing::expect_every_bit_flip_safe(sample_payloads(), try_parse);
}

TEST(MhRobustness, RandomMultiByteCorruptionIsSafe) {
  testing::random_multi_byte_corruption(sample_payloads(), try_parse, 20000, 5);
}

// Header fields set to extreme values (offsets, counts, sizes) with the payload size kept.
TEST(MhRobustness, HostileHeaderFields) {
  namespace F = mh_format;
  testing::hostile_header_fields(sample_payloads(),
                                 {F::kOffSize, F::kOffRootBlock, F::kOffStreamBytes, F::kOffBlockCount,
                                  F::kOffRecordCount, F::kOffValueCount},
                                 {F::kOffLevels, F::kOffOffsetWidth, F::kOffSkipLevel, F::kOffRootMask}, try_parse);
}

TEST(MhRobustness, MagicAndVersion) {
  testing::expect_magic_and_version_checked(sample_payloads()[3], mh_format::kOffVersion, mh_format::kFormatVersion,
                                            [](const std::vector<uint8_t>& q) { return MhTileView::parse(q); });
}

}  // namespace
}  // namespace shadowtiles
