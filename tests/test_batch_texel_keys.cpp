// BatchTexelKeys (the batch query's sort keys) and morton_encode16: both key layouts give the
// texel's Morton code and coordinates back, at the edges of their ranges and at random texels, and
// no texel's key is the off-map key.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "client/batch_texel_keys.hpp"
#include "codec/morton.hpp"

namespace shadowtiles {
namespace {

TEST(MortonEncode16, EqualsMortonEncodeForEveryValueOfOneAxisAndRandomPairs) {
  for (uint32_t x = 0; x < (1u << 16); ++x) {
    ASSERT_EQ(morton_encode16(x, 0), morton_encode(x, 0)) << x;
    ASSERT_EQ(morton_encode16(0, x), morton_encode(0, x)) << x;
    ASSERT_EQ(morton_encode16(x, 0xFFFF - x), morton_encode(x, 0xFFFF - x)) << x;
  }
  std::mt19937 rng(5);
  for (int i = 0; i < 100000; ++i) {
    const uint32_t u = rng() & 0xFFFF, v = rng() & 0xFFFF;
    ASSERT_EQ(morton_encode16(u, v), morton_encode(u, v)) << u << ", " << v;
  }
}

void expect_round_trips(unsigned resolution_log2, bool packed) {
  const BatchTexelKeys keys = BatchTexelKeys::for_key_bits(2 * resolution_log2);
  EXPECT_EQ(keys.packed(), packed) << resolution_log2;
  const uint32_t last = (1u << resolution_log2) - 1;
  std::vector<std::pair<uint32_t, uint32_t>> texels = {{0, 0}, {last, 0}, {0, last}, {last, last}, {last / 2, last / 2 + 1}};
  std::mt19937 rng(resolution_log2);
  for (int i = 0; i < 20000; ++i) texels.push_back({rng() & last, rng() & last});
  for (auto [u, v] : texels) {
    const uint64_t key = packed ? BatchTexelKeys::make_packed(u, v) : BatchTexelKeys::make_wide(u, v);
    ASSERT_EQ(keys.code(key), morton_encode(u, v)) << u << ", " << v << " at 2^" << resolution_log2;
    ASSERT_EQ(keys.u(key), u);
    ASSERT_EQ(keys.v(key), v);
    ASSERT_NE(key, BatchTexelKeys::kOffMapKey);
  }
}

TEST(BatchTexelKeys, MapsUpTo2To15KeepTheCoordinatesBesideTheCode) {
  for (unsigned log2 = 0; log2 <= 15; ++log2) expect_round_trips(log2, true);
}

TEST(BatchTexelKeys, WiderMapsUpTo2To20DeinterleaveTheCode) {
  for (unsigned log2 = 16; log2 <= 20; ++log2) expect_round_trips(log2, false);
}

TEST(BatchTexelKeys, CodesOrderLikeMortonCodes) {
  // The sort orders by code(): packed keys must order texels as their Morton codes do, whatever
  // the coordinates stored above them.
  const BatchTexelKeys keys = BatchTexelKeys::for_key_bits(30);
  auto make = BatchTexelKeys::make_packed;
  EXPECT_LT(keys.code(make(1, 0)), keys.code(make(0, 1)));
  EXPECT_LT(keys.code(make(0x7FFF, 0x7FFE)), keys.code(make(0x7FFE, 0x7FFF)));
  EXPECT_LT(keys.code(make(0x7FFF, 0)), keys.code(make(0, 0x4000)));
}

}  // namespace
}  // namespace shadowtiles
