// The SST decoder against hostile payloads, multi-block ones included: every truncation, random
// multi-byte corruption, hostile header fields, wrong magic and version, non-finite values. Each must give an
// error or a tile whose lookups stay in bounds and finite (run under ASan: -DSHADOWTILES_SANITIZE=ON).
// Every trial copies the bytes into an exact-size buffer so a read past the end is caught.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "builder/mh_synthetic.hpp"
#include "builder/sst_encoder.hpp"
#include "codec/decoded_tile.hpp"
#include "codec/sst_format.hpp"
#include "codec/sst_tile_view.hpp"
#include "tests/payload_attacks.hpp"

namespace shadowtiles {
namespace {

namespace F = sst_format;

// Small tiles holding every node kind (one, constant, plane, dense, internal) and, at 256, several
// blocks.
testing::Payloads sample_payloads() {
  return testing::encode_sample_tiles({MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                                       MhSyntheticKind::closed_plane, MhSyntheticKind::boxes_and_misses},
                                      [](const TileIntervals& tile) {
                                        return testing::Payloads{*encode_sst_tile(tile)};
                                      });
}

std::vector<uint8_t> multi_block_payload() {
  return *encode_sst_tile(make_synthetic_tile(MhSyntheticKind::boxes_and_misses, 256, 4));
}

void exercise(const DecodedTile& tile) {
  const uint32_t n = tile.size();
  const uint32_t step = n > 64 ? 7 : 1;
  for (uint32_t v = 0; v < n; v += step)
    for (uint32_t u = 0; u < n; u += step)
      for (unsigned level : {0u, 1u, 3u, 255u}) ASSERT_TRUE(std::isfinite(tile.value(u, v, level)));
  (void)tile.lit_count(0, 0, n, n, 0.5f);
  if (n >= 3) {
    (void)tile.lit_count(0, 0, 3, 3, 0.5f);
    (void)tile.lit_count(n - 3, n - 3, 3, 3, 0.5f);
  }
  (void)tile.size_breakdown();
}

bool try_decode(const std::vector<uint8_t>& bytes) {
  return testing::parse_exact(
      bytes, [](std::span<const uint8_t> exact) { return decode_tile(store::Method::sst, exact); },
      [](const std::shared_ptr<const DecodedTile>& tile) { exercise(*tile); });
}

void put_u32(std::vector<uint8_t>& p, size_t at, uint32_t x) { std::memcpy(p.data() + at, &x, 4); }

TEST(SstRobustness, OriginalsDecode) {
  for (const auto& p : sample_payloads()) EXPECT_TRUE(try_decode(p));
  EXPECT_TRUE(try_decode(multi_block_payload()));
}

TEST(SstRobustness, EveryTruncationIsAnError) {
  auto payloads = sample_payloads();
  payloads.push_back(multi_block_payload());
  for (const auto& p : payloads)
    for (size_t len = 0; len < p.size(); ++len)
      ASSERT_FALSE(try_decode(std::vector<uint8_t>(p.begin(), p.begin() + len))) << "length " << len;
}



TEST(SstRobustness, RandomCorruptionIsHandled) {
  const auto base = multi_block_payload();
  std::mt19937 rng(3);
  for (int trial = 0; trial < 400; ++trial) {
    auto p = base;
    const int bytes = 1 + int(rng() % 8);
    for (int k = 0; k < bytes; ++k) p[rng() % p.size()] = uint8_t(rng());
    (void)try_decode(p);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(SstRobustness, HostileHeaderFields) {
  const auto base = sample_payloads()[2];  // 32x32 steps
  auto with = [&](size_t at, uint32_t value) {
    auto p = base;
    put_u32(p, at, value);
    return p;
  };
  EXPECT_FALSE(try_decode(with(F::kOffSize, 0)));
  EXPECT_FALSE(try_decode(with(F::kOffSize, 48)));
  EXPECT_FALSE(try_decode(with(F::kOffSize, 1u << 31)));
  EXPECT_FALSE(try_decode(with(F::kOffSize, 64)));
  EXPECT_FALSE(try_decode(with(F::kOffBlockSide, 16)));
  EXPECT_FALSE(try_decode(with(F::kOffBlocksPerSide, 2)));
  EXPECT_FALSE(try_decode(with(F::kOffBlocksPerSide, 0xFFFFFFFFu)));
  EXPECT_FALSE(try_decode(with(F::kOffNodeBytes, 0xFFFFFFFFu)));
  EXPECT_FALSE(try_decode(with(F::kOffNodeBytes, 0)));
  EXPECT_FALSE(try_decode(with(F::kHeaderBytes, 1)));  // the one block's grid offset
  auto magic = base;
  magic[0] = 'X';
  EXPECT_FALSE(try_decode(magic));
  auto flags = base;
  flags[F::kOffFlags] = 1;
  EXPECT_FALSE(try_decode(flags));
  auto newer = base;
  newer[F::kOffVersion] = F::kFormatVersion + 1;
  std::vector<uint8_t> exact(newer);
  auto tile = decode_tile(store::Method::sst, exact);
  ASSERT_FALSE(tile.ok());
  EXPECT_EQ(tile.error().code, ErrorCode::unsupported);
}

TEST(SstRobustness, NonFiniteStoredValuesAreRejected) {
  // One block holding a single constant leaf: [header | grid | width | tag | f32].
  TileIntervals tile;
  tile.size = 4;
  tile.texels.assign(16, DepthInterval{0.25f, 0.5f});
  auto p = *encode_sst_tile(tile);
  ASSERT_EQ(p.size(), F::kHeaderBytes + 4 + 1 + F::kConstantBytes);
  ASSERT_EQ(F::kind_of(p[F::kHeaderBytes + 5]), F::kConstant);
  for (float bad : {std::nanf(""), std::numeric_limits<float>::infinity()}) {
    auto q = p;
    std::memcpy(q.data() + q.size() - 4, &bad, 4);
    EXPECT_FALSE(try_decode(q));
  }
}


}  // namespace
}  // namespace shadowtiles
