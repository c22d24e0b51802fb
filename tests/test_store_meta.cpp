// StoreMeta::parse on hostile numbers: every count in the meta is an integer that fits its type, or the
// meta is corrupt_data (fuzz_store_meta regression: a 50-digit resolution was cast from a double,
// undefined behaviour under UBSan); the nearly-closed misplaced-area field's default for older stores.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "codec/store_meta.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

// The regression input: a real build's meta (fzk_haus, six methods) with its resolution mutated.
nlohmann::json regression_meta() {
  const auto path = std::filesystem::path(SHADOWTILES_SOURCE_DIR) / "fuzz/regressions/fuzz_store_meta/resolution-of-50-digits";
  auto text = testing::read_file(path);
  EXPECT_FALSE(text.empty()) << path;
  return nlohmann::json::parse(text);
}

TEST(StoreMeta, HugeOrFractionalCountsAreCorruptNotCast) {
  nlohmann::json meta = regression_meta();
  auto parsed = StoreMeta::parse(meta.dump());
  ASSERT_FALSE(parsed.ok());
  EXPECT_EQ(parsed.error().code, ErrorCode::corrupt_data);
  EXPECT_NE(parsed.error().message.find("bad 'resolution': not an integer in [0, 4294967295]"), std::string::npos)
      << parsed.error().message;

  // The same meta with a resolution that fits parses: the rule refuses the number, nothing else.
  meta["resolution"] = 1024;
  auto repaired = StoreMeta::parse(meta.dump());
  ASSERT_TRUE(repaired.ok()) << repaired.error().message;
  EXPECT_EQ(repaired->resolution, 1024u);

  for (const char* bad : {"4294967296", "-1", "1024.5", "1e30", "-1e30", "\"1024\""}) {
    meta["resolution"] = nlohmann::json::parse(bad);
    auto refused = StoreMeta::parse(meta.dump());
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_EQ(refused.error().code, ErrorCode::corrupt_data) << bad;
  }
  // Signed and 64-bit fields: the format version (int) and the triangle count (uint64).
  meta["resolution"] = 1024;
  meta["format_version"] = 1e300;
  EXPECT_FALSE(StoreMeta::parse(meta.dump()).ok());
  meta["format_version"] = repaired->format_version;
  meta["scene"]["triangles"] = -5;
  EXPECT_FALSE(StoreMeta::parse(meta.dump()).ok());
  meta["scene"]["triangles"] = 18446744073709551615ull;
  EXPECT_TRUE(StoreMeta::parse(meta.dump()).ok());
}

// The nearly-closed test's misplaced-area budget: stores built before it have no field and reload
// their scenes with 0 (any misplaced sample refused, the rule they were built with); a value outside
// [0, 1] is corrupt; a built meta round-trips it.
TEST(StoreMeta, NearlyClosedMisplacedAreaDefaultsToTheOldRule) {
  nlohmann::json meta = regression_meta();
  meta["resolution"] = 1024;
  ASSERT_FALSE(meta["nearly_closed"].contains("max_misplaced_area"));
  auto old = StoreMeta::parse(meta.dump());
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_TRUE(old->nearly_closed);
  EXPECT_EQ(old->nearly_closed_max_misplaced_area, 0.0);

  meta["nearly_closed"]["max_misplaced_area"] = 0.01;
  auto current = StoreMeta::parse(meta.dump());
  ASSERT_TRUE(current.ok()) << current.error().message;
  EXPECT_EQ(current->nearly_closed_max_misplaced_area, 0.01);
  auto again = StoreMeta::parse(current->to_json().dump());
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again->nearly_closed_max_misplaced_area, 0.01);

  for (double bad : {-0.5, 1.5}) {
    meta["nearly_closed"]["max_misplaced_area"] = bad;
    auto refused = StoreMeta::parse(meta.dump());
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_EQ(refused.error().code, ErrorCode::corrupt_data) << bad;
  }
}

}  // namespace
}  // namespace shadowtiles
