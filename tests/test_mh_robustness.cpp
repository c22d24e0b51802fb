// The MH decoder against hostile payloads, skip-list payloads (top trees) included: bit flips,
// random corruption, hostile header fields, wrong magic and version. Each must give an error or a view whose lookups stay in bounds (run under ASan:
// -DSHADOWTILES_SANITIZE=ON). Every trial copies the bytes into an exact-size buffer so a read past
// the end is caught.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/mh_format.hpp"

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
  uint64_t accepted = 0, trials = 0;
  for (const auto& p : sample_payloads()) {
    for (size_t byte = 0; byte < p.size(); ++byte)
      for (unsigned bit = 0; bit < 8; ++bit) {
        auto q = p;
        q[byte] ^= uint8_t(1u << bit);
        accepted += try_parse(q);
        ++trials;
      }
  }
  // Flipped value bits are legitimately accepted (a different finite value); structure flips are not.
  EXPECT_LT(accepted, trials);
  RecordProperty("accepted", std::to_string(accepted) + "/" + std::to_string(trials));
}

TEST(MhRobustness, RandomMultiByteCorruptionIsSafe) {
  std::mt19937 rng(5);
  const auto payloads = sample_payloads();
  for (int trial = 0; trial < 20000; ++trial) {
    auto q = payloads[rng() % payloads.size()];
    const unsigned edits = 1 + rng() % 4;
    for (unsigned e = 0; e < edits; ++e) q[rng() % q.size()] = uint8_t(rng());
    try_parse(q);
  }
}

// Header fields set to extreme values (offsets, counts, sizes) with the payload size kept.
TEST(MhRobustness, HostileHeaderFields) {
  namespace F = mh_format;
  for (const auto& p : sample_payloads()) {
    for (size_t field : {F::kOffSize, F::kOffRootBlock, F::kOffStreamBytes, F::kOffBlockCount, F::kOffRecordCount,
                         F::kOffValueCount}) {
      for (uint32_t value : {0u, 1u, 0x7fffffffu, 0xffffffffu, uint32_t(p.size())}) {
        auto q = p;
        std::memcpy(q.data() + field, &value, 4);
        try_parse(q);
      }
    }
    for (size_t field : {F::kOffLevels, F::kOffOffsetWidth, F::kOffSkipLevel, F::kOffRootMask})
      for (unsigned value = 0; value < 256; value += 3) {
        auto q = p;
        q[field] = uint8_t(value);
        try_parse(q);
      }
  }
}

TEST(MhRobustness, MagicAndVersion) {
  auto p = sample_payloads()[3];
  auto q = p;
  q[0] = 'X';
  auto r = MhTileView::parse(q);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::corrupt_data);
  q = p;
  q[mh_format::kOffVersion] = uint8_t(mh_format::kFormatVersion + 1);
  r = MhTileView::parse(q);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::unsupported);
  q = p;
  q[mh_format::kOffVersion] = 0;
  EXPECT_FALSE(MhTileView::parse(q).ok());
}


}  // namespace
}  // namespace shadowtiles
