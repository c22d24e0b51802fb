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

std::vector<std::vector<uint8_t>> sample_payloads() {
  std::vector<std::vector<uint8_t>> out;
  for (MhSyntheticKind kind : {MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                               MhSyntheticKind::boxes_and_misses, MhSyntheticKind::all_miss}) {
    for (uint32_t size : {1u, 8u, 32u}) {
      auto tree = build_mh(make_synthetic_tile(kind, size, size + 17));
      auto merged = merge_mmh(*tree);
      out.push_back(*encode_mh(*tree));
      out.push_back(*encode_mh(*merged));
      MhEncodeOptions skip;
      skip.embed_skip_list = true;
      skip.skip_level = 2;
      out.push_back(*encode_mh(*merged, skip));
    }
  }
  return out;
}

// Exercises every read path of an accepted view; values must be finite.
void exercise(const MhTileView& view) {
  const uint32_t n = view.size();
  for (uint32_t v = 0; v < n; ++v)
    for (uint32_t u = 0; u < n; ++u)
      for (unsigned level : {0u, 1u, 3u, kMhAllLevels}) ASSERT_TRUE(std::isfinite(view.lookup(u, v, level)));
  if (n >= 3) {
    (void)view.pcf_lit_fraction(0, 0, 3, 0.5f, 0.0f);
    (void)view.pcf_lit_fraction(n - 3, n - 3, 3, 0.5f, 0.0f);
    (void)view.pcf_lit_fraction(0, 0, n, 0.5f, 0.0f);
  }
}

bool try_parse(const std::vector<uint8_t>& bytes) {
  std::vector<uint8_t> exact(bytes);  // exact-size heap buffer: ASan sees any overrun
  auto view = MhTileView::parse(std::span<const uint8_t>(exact.data(), exact.size()));
  if (!view.ok()) {
    EXPECT_TRUE(view.error().code == ErrorCode::corrupt_data || view.error().code == ErrorCode::unsupported);
    return false;
  }
  exercise(*view);
  return true;
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
