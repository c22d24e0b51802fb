// The raw tile payload (codec/raw_tile.hpp): header checks, finite values, the version-0 layout.
// RawTile.NanValueIsCorrupt is the regression test of the fuzz_tile_raw crash (a NaN texel was
// accepted and answered every query as shadowed).
#include "codec/raw_tile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "codec/decoded_tile.hpp"

namespace shadowtiles {
namespace {

std::vector<float> ramp(uint32_t size) {
  std::vector<float> values(size_t(size) * size);
  for (size_t i = 0; i < values.size(); ++i) values[i] = float(i) / float(values.size());
  return values;
}

ErrorCode parse_error(const std::vector<uint8_t>& payload) {
  auto view = RawTileView::parse(payload);
  EXPECT_FALSE(view.ok());
  return view.ok() ? ErrorCode::invalid_input : view.error().code;
}

TEST(RawTile, RoundTripWithHeader) {
  const auto values = ramp(8);
  const auto payload = encode_raw_tile(8, values);
  ASSERT_EQ(payload.size(), kRawTileHeaderSize + 64 * 4);
  EXPECT_EQ(std::memcmp(payload.data(), "STRW", 4), 0);
  auto view = RawTileView::parse(payload);
  ASSERT_TRUE(view.ok()) << view.error().message;
  EXPECT_EQ(view->size(), 8u);
  for (uint32_t v = 0; v < 8; ++v)
    for (uint32_t u = 0; u < 8; ++u) EXPECT_EQ(view->value(u, v), values[v * 8 + u]);
}

// PCF boxes read straight from the array count what comparing every texel's value counts, for
// every box of a 16x16 tile with misses (1) among the values.
TEST(RawTile, PcfCountsEqualPerTexelComparisons) {
  const uint32_t size = 16;
  std::vector<float> values = ramp(size);
  for (size_t i = 0; i < values.size(); i += 7) values[i] = 1.0f;  // misses are stored as 1
  auto tile = decode_raw_tile(encode_raw_tile(size, values));
  ASSERT_TRUE(tile.ok()) << tile.error().message;
  for (float threshold : {0.0f, 0.3f, 0.5f, 0.97f, 2.0f})
    for (uint32_t v0 = 0; v0 < size; ++v0)
      for (uint32_t u0 = 0; u0 < size; ++u0)
        for (uint32_t k = 1; u0 + k <= size && v0 + k <= size && k <= 7; k += 2) {
          uint32_t expected = 0;
          for (uint32_t v = v0; v < v0 + k; ++v)
            for (uint32_t u = u0; u < u0 + k; ++u) expected += threshold <= values[v * size + u];
          ASSERT_EQ((*tile)->lit_count(u0, v0, k, k, threshold), expected) << u0 << "," << v0 << " k " << k;
          ASSERT_EQ((*tile)->lit(u0, v0, threshold), threshold <= values[v0 * size + u0]);
          const auto sample = (*tile)->sample(u0, v0, threshold);
          ASSERT_EQ(sample.value, values[v0 * size + u0]);
          ASSERT_EQ(sample.lit, threshold <= sample.value);
        }
}

TEST(RawTile, NanValueIsCorrupt) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    auto values = ramp(4);
    values[6] = bad;
    const auto payload = encode_raw_tile(4, values);
    auto view = RawTileView::parse(payload);
    ASSERT_FALSE(view.ok());
    EXPECT_EQ(view.error().code, ErrorCode::corrupt_data);
    EXPECT_NE(view.error().message.find("non-finite value at texel (2, 1)"), std::string::npos) << view.error().message;
    auto tile = decode_tile(store::Method::raw, payload);
    ASSERT_FALSE(tile.ok());
    EXPECT_EQ(tile.error().code, ErrorCode::corrupt_data);
  }
}

TEST(RawTile, HeaderChecks) {
  const auto good = encode_raw_tile(4, ramp(4));
  auto bad_magic = good;
  bad_magic[3] = 'X';
  EXPECT_EQ(parse_error(bad_magic), ErrorCode::corrupt_data);
  auto newer = good;
  newer[4] = kRawTileFormatVersion + 1;
  EXPECT_EQ(parse_error(newer), ErrorCode::unsupported);
  auto version0 = good;
  version0[4] = 0;
  EXPECT_EQ(parse_error(version0), ErrorCode::corrupt_data);
  auto reserved = good;
  reserved[7] = 1;
  EXPECT_EQ(parse_error(reserved), ErrorCode::corrupt_data);
  auto not_pow2 = good;
  not_pow2[8] = 3;
  EXPECT_EQ(parse_error(not_pow2), ErrorCode::corrupt_data);
  auto huge = good;
  huge[8] = 0, huge[9] = 0, huge[10] = 1;  // 65536
  EXPECT_EQ(parse_error(huge), ErrorCode::corrupt_data);
  auto truncated = good;
  truncated.pop_back();
  EXPECT_EQ(parse_error(truncated), ErrorCode::corrupt_data);
  auto trailing = good;
  trailing.push_back(0);
  EXPECT_EQ(parse_error(trailing), ErrorCode::corrupt_data);
  EXPECT_EQ(parse_error(std::vector<uint8_t>(good.begin(), good.begin() + 8)), ErrorCode::corrupt_data);
}

TEST(RawTile, VersionZeroPayloadsStillRead) {
  // Stores built before the header: u32 size, then the texels.
  const auto values = ramp(4);
  std::vector<uint8_t> legacy(4 + values.size() * 4);
  const uint32_t size = 4;
  std::memcpy(legacy.data(), &size, 4);
  std::memcpy(legacy.data() + 4, values.data(), values.size() * 4);
  auto view = RawTileView::parse(legacy);
  ASSERT_TRUE(view.ok()) << view.error().message;
  EXPECT_EQ(view->value(3, 2), values[11]);
  float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(legacy.data() + 4 + 5 * 4, &nan, 4);
  EXPECT_EQ(parse_error(legacy), ErrorCode::corrupt_data);
}

}  // namespace
}  // namespace shadowtiles
