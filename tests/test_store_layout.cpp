// The store's layout (store/store_layout.hpp): the progress record's codec round-trips, refuses
// every malformed record instead of guessing, and progress keys sort in tile order (big-endian).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "store/store_layout.hpp"

namespace shadowtiles::store {
namespace {

TEST(StoreLayout, ProgressRecordRoundTrips) {
  const float inf = std::numeric_limits<float>::infinity();
  for (ProgressRecord r : {ProgressRecord{true, 0.25f, 0.75f}, ProgressRecord{false, 1.0f, inf},
                           ProgressRecord{true, 0.5f, 0.5f}}) {
    auto bytes = encode_progress(r);
    auto back = decode_progress(bytes);
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->stored, r.stored);
    EXPECT_EQ(back->root_lower, r.root_lower);
    EXPECT_EQ(back->root_upper, r.root_upper);
  }
  // FORMAT: stored byte, then lower and upper as f32 little-endian.
  auto bytes = encode_progress({true, 1.0f, 2.0f});
  const std::array<uint8_t, 9> expected = {1, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x40};
  EXPECT_EQ(bytes, expected);
}

TEST(StoreLayout, MalformedProgressRecordsAreErrors) {
  auto good = encode_progress({true, 0.25f, 0.75f});
  for (size_t n = 0; n < good.size(); ++n) EXPECT_FALSE(decode_progress(std::span(good.data(), n)).ok()) << n;
  std::vector<uint8_t> longer(good.begin(), good.end());
  longer.push_back(0);
  EXPECT_FALSE(decode_progress(longer).ok());
  auto flag = good;
  flag[0] = 2;
  EXPECT_FALSE(decode_progress(flag).ok()) << "stored flag other than 0/1";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(decode_progress(encode_progress({true, nan, 1.0f})).ok());
  EXPECT_FALSE(decode_progress(encode_progress({true, 0.5f, nan})).ok());
  EXPECT_FALSE(decode_progress(encode_progress({true, 0.75f, 0.25f})).ok()) << "inverted";
  auto error = decode_progress(flag);
  EXPECT_EQ(error.error().code, ErrorCode::corrupt_data);
}

TEST(StoreLayout, ProgressKeysSortInTileOrderAndRoundTrip) {
  auto a = progress_key(1, 0x01020304u), b = progress_key(1, 0x01020305u), c = progress_key(2, 0);
  EXPECT_LT(a, b);
  EXPECT_LT(b, c);
  auto tile = decode_progress_key(c);
  ASSERT_TRUE(tile.ok());
  EXPECT_EQ(tile->x, 2u);
  EXPECT_EQ(tile->y, 0u);
  EXPECT_FALSE(decode_progress_key(std::span(c.data(), 7)).ok());
  EXPECT_EQ(top_tree_key(Method::dagmh), "top/dagmh");
}

}  // namespace
}  // namespace shadowtiles::store
