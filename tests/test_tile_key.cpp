#include "store/tile_key.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <tuple>
#include <vector>

#include "store/method.hpp"

namespace shadowtiles::store {
namespace {

TileKey random_key(std::mt19937_64& rng) {
  const auto methods = all_methods();
  // Mix small and extreme coordinates so both the low and the high bytes decide the order.
  auto coord = [&]() -> uint32_t {
    switch (rng() % 3) {
      case 0: return static_cast<uint32_t>(rng() % 4);
      case 1: return static_cast<uint32_t>(rng());
      default: return 0xffffffffu - static_cast<uint32_t>(rng() % 4);
    }
  };
  return TileKey{methods[rng() % methods.size()], static_cast<uint8_t>(rng() % 4 == 0 ? 255 : rng() % 20),
                 coord(), coord()};
}

TEST(TileKey, MemcmpOrderEqualsNumericOrder) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const TileKey a = random_key(rng);
    const TileKey b = random_key(rng);
    const auto ea = encode_tile_key(a);
    const auto eb = encode_tile_key(b);
    const int cmp = std::memcmp(ea.data(), eb.data(), kTileKeySize);
    const auto numeric = std::make_tuple(static_cast<uint8_t>(a.method), a.level, a.x, a.y) <=>
                         std::make_tuple(static_cast<uint8_t>(b.method), b.level, b.x, b.y);
    EXPECT_EQ(cmp < 0, numeric < 0) << i;
    EXPECT_EQ(cmp == 0, numeric == 0) << i;
    EXPECT_EQ(a < b, numeric < 0);  // the defaulted operator agrees too
  }
}

TEST(TileKey, KnownBytesAreBigEndian) {
  const auto bytes = encode_tile_key({Method::mh, 3, 0x01020304u, 0xa0b0c0d0u});
  const std::array<uint8_t, 10> expected = {2, 3, 0x01, 0x02, 0x03, 0x04, 0xa0, 0xb0, 0xc0, 0xd0};
  EXPECT_EQ(bytes, expected);
}

TEST(TileKey, RoundTrip) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 5000; ++i) {
    const TileKey key = random_key(rng);
    const auto bytes = encode_tile_key(key);
    Result<TileKey> decoded = decode_tile_key(bytes);
    ASSERT_TRUE(decoded.ok()) << decoded.error().message;
    EXPECT_EQ(*decoded, key);
  }
}

TEST(TileKey, WrongLengthIsAnError) {
  const auto bytes = encode_tile_key({Method::raw, 0, 1, 2});
  std::vector<uint8_t> buffer(bytes.begin(), bytes.end());
  for (size_t length = 0; length < kTileKeySize; ++length) {
    Result<TileKey> decoded = decode_tile_key(std::span(buffer).first(length));
    ASSERT_FALSE(decoded.ok()) << length;
    EXPECT_EQ(decoded.error().code, ErrorCode::invalid_input);
  }
  buffer.push_back(0);
  EXPECT_FALSE(decode_tile_key(buffer).ok());
}

TEST(TileKey, UnknownMethodByteIsAnError) {
  auto bytes = encode_tile_key({Method::raw, 0, 1, 2});
  for (int byte : {0, 7, 200, 255}) {
    bytes[0] = static_cast<uint8_t>(byte);
    Result<TileKey> decoded = decode_tile_key(bytes);
    ASSERT_FALSE(decoded.ok()) << byte;
    EXPECT_EQ(decoded.error().code, ErrorCode::invalid_input);
  }
}

TEST(TileKey, PrefixMatchesEncodedKeys) {
  const auto key = encode_tile_key({Method::dagmh, 9, 5, 6});
  const auto prefix = tile_key_prefix(Method::dagmh, 9);
  EXPECT_EQ(0, std::memcmp(key.data(), prefix.data(), prefix.size()));
}

TEST(Method, NamesRoundTrip) {
  for (Method method : all_methods()) {
    Result<Method> parsed = parse_method(method_name(method));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, method);
    Result<Method> from_byte = method_from_byte(static_cast<uint8_t>(method));
    ASSERT_TRUE(from_byte.ok());
    EXPECT_EQ(*from_byte, method);
  }
  EXPECT_STREQ(method_name(Method::dagmh), "dagmh");
  EXPECT_EQ(static_cast<uint8_t>(Method::sst), 6);  // FORMAT: numbers must never change
}

TEST(Method, UnknownNamesAreInvalid) {
  for (const char* name : {"", "MH", "m h", "dag-mh", "rawx", "raw "}) {
    Result<Method> parsed = parse_method(name);
    ASSERT_FALSE(parsed.ok()) << name;
    EXPECT_EQ(parsed.error().code, ErrorCode::invalid_input);
  }
}

TEST(Method, ListParsesDedupsAndKeepsOrder) {
  Result<std::vector<Method>> list = parse_method_list("dagmh, raw,mh,raw,dagmh");
  ASSERT_TRUE(list.ok()) << list.error().message;
  EXPECT_EQ(*list, (std::vector<Method>{Method::dagmh, Method::raw, Method::mh}));
  for (const char* bad : {"", " ", "raw,", ",raw", "raw,,mh", "raw,nope"}) {
    Result<std::vector<Method>> parsed = parse_method_list(bad);
    ASSERT_FALSE(parsed.ok()) << bad;
    EXPECT_EQ(parsed.error().code, ErrorCode::invalid_input);
  }
}

}  // namespace
}  // namespace shadowtiles::store
