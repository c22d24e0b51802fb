#include "store/tile_info.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace shadowtiles::store {
namespace {

TEST(TileInfo, RoundTripsEveryField) {
  TileInfo info{true, 0.25f, std::numeric_limits<float>::infinity(), 123456789012ull, 42};
  auto bytes = encode_tile_info(info);
  EXPECT_EQ(bytes[0], kTileInfoFormatVersion);
  auto back = decode_tile_info(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(*back, info);
  TileInfo flat{false, 1.0f, 1.0f, 7, 9};
  auto flat_back = decode_tile_info(encode_tile_info(flat));
  ASSERT_TRUE(flat_back.ok());
  EXPECT_EQ(*flat_back, flat);
}

TEST(TileInfo, MalformedRecordsAreErrors) {
  auto good = encode_tile_info({true, 0.1f, 0.2f, 1, 2});
  EXPECT_EQ(decode_tile_info(std::span(good).first(27)).error().code, ErrorCode::corrupt_data);
  auto newer = good;
  newer[0] = kTileInfoFormatVersion + 1;
  EXPECT_EQ(decode_tile_info(newer).error().code, ErrorCode::unsupported);
  auto zero = good;
  zero[0] = 0;
  EXPECT_EQ(decode_tile_info(zero).error().code, ErrorCode::corrupt_data);
  auto flags = good;
  flags[1] = 0x80;
  EXPECT_EQ(decode_tile_info(flags).error().code, ErrorCode::corrupt_data);
  auto inverted = encode_tile_info({true, 0.5f, 0.2f, 1, 2});
  EXPECT_EQ(decode_tile_info(inverted).error().code, ErrorCode::corrupt_data);
  auto nan = encode_tile_info({true, std::numeric_limits<float>::quiet_NaN(), 0.2f, 1, 2});
  EXPECT_EQ(decode_tile_info(nan).error().code, ErrorCode::corrupt_data);
}

}  // namespace
}  // namespace shadowtiles::store
