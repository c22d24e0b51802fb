// json_integer_in (codec/json_integer.hpp): a JSON integer in range comes back exact; floats,
// strings and integers outside the range (either sign, any width) are refused, never cast.
#include "codec/json_integer.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

namespace shadowtiles {
namespace {

using nlohmann::json;

TEST(JsonInteger, InRangeIntegersComeBackExact) {
  EXPECT_EQ(json_integer_in<uint32_t>(json(4096), 0, UINT32_MAX), 4096u);
  EXPECT_EQ(json_integer_in<uint32_t>(json(uint64_t(UINT32_MAX)), 0, UINT32_MAX), UINT32_MAX);
  EXPECT_EQ(json_integer_in<int32_t>(json(-7), INT32_MIN, INT32_MAX), -7);
  EXPECT_EQ(json_integer_in<uint64_t>(json(UINT64_MAX), 0, UINT64_MAX), UINT64_MAX);
  EXPECT_EQ(json_integer_in<int64_t>(json(INT64_MIN), INT64_MIN, INT64_MAX), INT64_MIN);
  EXPECT_EQ(json_integer_in<uint16_t>(json(1), 1, 256), 1u);
  EXPECT_EQ(json_integer_in<uint16_t>(json(256), 1, 256), 256u);
}

TEST(JsonInteger, OutOfRangeIntegersAreRefused) {
  EXPECT_FALSE(json_integer_in<uint32_t>(json(uint64_t(UINT32_MAX) + 1), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json(-1), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint64_t>(json(INT64_MIN), 0, UINT64_MAX));
  EXPECT_FALSE(json_integer_in<int32_t>(json(int64_t(INT32_MIN) - 1), INT32_MIN, INT32_MAX));
  EXPECT_FALSE(json_integer_in<int64_t>(json(UINT64_MAX), INT64_MIN, INT64_MAX));
  EXPECT_FALSE(json_integer_in<uint16_t>(json(0), 1, 256));
  EXPECT_FALSE(json_integer_in<uint16_t>(json(257), 1, 256));
}

TEST(JsonInteger, NonIntegersAreRefusedNotCast) {
  EXPECT_FALSE(json_integer_in<uint32_t>(json(1024.0), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json(1024.5), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json(1e300), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json::parse("1e400", nullptr, false), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json("12"), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json(true), 0, UINT32_MAX));
  EXPECT_FALSE(json_integer_in<uint32_t>(json(nullptr), 0, UINT32_MAX));
  // 50 digits: nlohmann parses it as a float, whose cast to uint32_t is undefined.
  EXPECT_FALSE(json_integer_in<uint32_t>(json::parse("12345678901234567890123456789012345678901234567890"), 0,
                                         UINT32_MAX));
}

}  // namespace
}  // namespace shadowtiles
