// Size breakdowns (DecodedTile::size_breakdown) and `shadowtiles inspect`: the named parts of every
// MH / MMH / DAG-MH payload add up to the payload exactly, on synthetic tiles and summed over a real
// store's tiles as inspect prints them.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/decoded_tile.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

uint64_t sum_of(const std::vector<DecodedTile::SizePart>& parts) {
  uint64_t sum = 0;
  for (const auto& part : parts) sum += part.bytes;
  return sum;
}

std::map<std::string, uint64_t> by_name(const std::vector<DecodedTile::SizePart>& parts) {
  std::map<std::string, uint64_t> m;
  for (const auto& part : parts) m[part.name] += part.bytes;
  return m;
}

TEST(DagMhInspect, BreakdownsSumToThePayload) {
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane,
                               MhSyntheticKind::steps, MhSyntheticKind::boxes_and_misses, MhSyntheticKind::all_miss})
    for (uint32_t size : {1u, 2u, 64u, 256u}) {
      const std::string what = std::string(synthetic_kind_name(kind)) + " " + std::to_string(size);
      auto tree = build_mh(make_synthetic_tile(kind, size, 7));
      ASSERT_TRUE(tree.ok()) << what;
      auto merged = merge_mmh(*tree);
      ASSERT_TRUE(merged.ok()) << what;
      const std::pair<store::Method, Result<std::vector<uint8_t>>> payloads[] = {
          {store::Method::mh, encode_mh(*tree)},
          {store::Method::mmh, encode_mh(*merged)},
          {store::Method::dagmh, encode_dagmh(*tree)}};
      for (const auto& [method, bytes] : payloads) {
        ASSERT_TRUE(bytes.ok()) << what;
        auto tile = decode_tile(method, *bytes);
        ASSERT_TRUE(tile.ok()) << what << ": " << tile.error().message;
        const auto parts = (*tile)->size_breakdown();
        ASSERT_FALSE(parts.empty()) << what;
        EXPECT_EQ(sum_of(parts), bytes->size()) << what << " " << store::method_name(method);
        EXPECT_EQ(by_name(parts).count("unaccounted"), 0u) << what;
        EXPECT_EQ(by_name(parts)["header"], 40u) << what;
      }
    }
}

// Parts that must be non-zero where the data calls for them: a DAG and treelets on a large tile,
// quantised values on the zero-width intervals of an open surface, raw floats on random intervals.
TEST(DagMhInspect, DagMhPartsReflectTheContent) {
  auto noisy = decode_tile(store::Method::dagmh,
                           *encode_dagmh(*build_mh(make_synthetic_tile(MhSyntheticKind::noisy_plane, 256, 3))));
  ASSERT_TRUE(noisy.ok());
  auto parts = by_name((*noisy)->size_breakdown());
  EXPECT_GT(parts["DAG node masks"], 0u);
  EXPECT_GT(parts["treelets"], 0u);
  EXPECT_GT(parts["multipliers"], 0u);
  EXPECT_GT(parts["grid constants"], 0u);
  EXPECT_GT(parts["difference bitmaps"], 0u);
  EXPECT_EQ(parts["chunk representatives"] % 5, 0u);

  auto random = decode_tile(store::Method::dagmh,
                            *encode_dagmh(*build_mh(make_synthetic_tile(MhSyntheticKind::random_intervals, 256, 3))));
  ASSERT_TRUE(random.ok());
  EXPECT_GT(by_name((*random)->size_breakdown())["raw float values"], 0u);

  auto mh = decode_tile(store::Method::mh, *encode_mh(*build_mh(make_synthetic_tile(MhSyntheticKind::steps, 256, 3))));
  ASSERT_TRUE(mh.ok());
  auto mh_parts = by_name((*mh)->size_breakdown());
  EXPECT_GT(mh_parts["inner node records"] + mh_parts["empty node records"], 0u);
  EXPECT_GT(mh_parts["leaf values"], 0u);
}

// A real store through the CLI: inspect --json lists per method the summed parts, equal to the
// summed payload bytes.
TEST(DagMhInspect, InspectPrintsPartsSummingToPayloadBytes) {
  testing::TempDir dir;
  const std::string store = (dir.path() / "s").string();
  std::string output;
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " build " +
                                     testing::shared_scene("nefertiti/nefertiti.obj").string() +
                                     " -r 512 --tile 128 -m raw,mh,mmh,dagmh -q --out " + store,
                                 &output),
            0)
      << output;
  output.clear();
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " inspect --json " + store + " 2>/dev/null", &output),
            0)
      << output;
  const auto report = nlohmann::json::parse(output);
  for (const char* method : {"mh", "mmh", "dagmh"}) {
    ASSERT_TRUE(report["methods"].contains(method)) << method;
    const auto& m = report["methods"][method];
    ASSERT_TRUE(m.contains("payload_parts")) << method;
    uint64_t sum = 0;
    for (const auto& part : m["payload_parts"]) sum += part["bytes"].get<uint64_t>();
    EXPECT_EQ(sum, m["payload_bytes"].get<uint64_t>()) << method;
    EXPECT_EQ(m["payload_parts"][0]["bytes"].get<uint64_t>(), 40u * m["tiles"].get<uint64_t>()) << method;
  }
  EXPECT_GT(report["methods"]["dagmh"]["dag"]["values"].get<uint64_t>(), 0u);
  output.clear();
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " inspect " + store + " 2>/dev/null", &output), 0);
  EXPECT_NE(output.find("dagmh payload parts:"), std::string::npos) << output;
  EXPECT_NE(output.find("multipliers"), std::string::npos) << output;
}

}  // namespace
}  // namespace shadowtiles
