// The DAG-MH parameter study: for_each_dagmh_parameter gives the same bytes as separate encodes,
// the shared-dictionary accounting, and `shadowtiles dagmh-study` on a small map agreeing with a
// store built by `shadowtiles build` with the same parameters.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "builder/dagmh_encoder.hpp"
#include "builder/dagmh_sharing_study.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_synthetic.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

TEST(DagMhStudy, EveryParameterPointIsTheSeparateEncode) {
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::steps, MhSyntheticKind::noisy_plane,
                               MhSyntheticKind::all_miss}) {
    auto tree = build_mh(make_synthetic_tile(kind, 128, 5));
    ASSERT_TRUE(tree.ok());
    unsigned visited = 0;
    Status s = for_each_dagmh_parameter(*tree, {2, 3, 4, 5}, {16, 32, 100}, [&](unsigned h, unsigned c, auto payload) {
      DagMhOptions o;
      o.treelet_height = h;
      o.chunk_size = c;
      auto expected = encode_dagmh(*tree, o);
      EXPECT_TRUE(expected.ok());
      EXPECT_TRUE(std::equal(payload.begin(), payload.end(), expected->begin(), expected->end()))
          << synthetic_kind_name(kind) << " H " << h << " C " << c;
      ++visited;
      return Status::success();
    });
    EXPECT_TRUE(s.ok());
    EXPECT_EQ(visited, 12u);
  }
  auto tree = build_mh(make_synthetic_tile(MhSyntheticKind::steps, 16, 5));
  EXPECT_FALSE(for_each_dagmh_parameter(*tree, {6}, {32}, [](auto, auto, auto) { return Status::success(); }).ok());
}

TEST(DagMhStudy, SharedDictionaryCountsEveryShapeOnce) {
  auto a = build_mh(make_synthetic_tile(MhSyntheticKind::steps, 256, 1));
  auto b = build_mh(make_synthetic_tile(MhSyntheticKind::random_intervals, 256, 2));
  ASSERT_TRUE(a.ok() && b.ok());
  auto ta = dagmh_topology(*a);
  ASSERT_TRUE(ta.ok());

  DagMhSharingStudy one;
  ASSERT_TRUE(one.add_tile(*a).ok());
  const DagMhSharingFigures single = one.figures();
  EXPECT_EQ(single.shared_nodes, ta->nodes.size());
  EXPECT_EQ(single.shared_treelets, ta->treelets.size());

  // The same tile three times: the dictionary does not grow; per-tile bytes triple.
  DagMhSharingStudy same;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(same.add_tile(*a).ok());
  const DagMhSharingFigures tripled = same.figures();
  EXPECT_EQ(tripled.shared_nodes, single.shared_nodes);
  EXPECT_EQ(tripled.shared_treelets, single.shared_treelets);
  EXPECT_EQ(tripled.per_tile_bytes, 3 * single.per_tile_bytes);
  EXPECT_EQ(tripled.dictionary_bytes, single.dictionary_bytes);

  // Two different tiles: the dictionary holds at most the sum of their shapes.
  DagMhSharingStudy mixed;
  ASSERT_TRUE(mixed.add_tile(*a).ok());
  ASSERT_TRUE(mixed.add_tile(*b).ok());
  auto tb = dagmh_topology(*b);
  ASSERT_TRUE(tb.ok());
  const DagMhSharingFigures both = mixed.figures();
  EXPECT_LE(both.shared_nodes, ta->nodes.size() + tb->nodes.size());
  EXPECT_GE(both.shared_nodes, std::max(ta->nodes.size(), tb->nodes.size()));
}

// The study's H = 4, C = 32 sizes equal the payload bytes of a real build of the same map.
TEST(DagMhStudy, CommandAgreesWithABuiltStore) {
  testing::TempDir dir;
  const std::string scene = testing::shared_scene("nefertiti/nefertiti.obj").string();
  const std::string store = (dir.path() / "s").string();
  std::string output;
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " build " + scene +
                                     " -r 512 --tile 256 -m mmh,dagmh -q --out " + store,
                                 &output),
            0)
      << output;
  output.clear();
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " inspect --json " + store + " 2>/dev/null", &output), 0)
      << output;
  const auto inspected = nlohmann::json::parse(output)["methods"];

  output.clear();
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " dagmh-study " + scene +
                                     " -r 256,512 --tile 256 --heights 2,4 --chunks 32,64 --lookups 300 --json -q"
                                     " 2>/dev/null",
                                 &output),
            0)
      << output;
  const auto report = nlohmann::json::parse(output);
  ASSERT_EQ(report["resolutions"].size(), 2u);
  const auto& r512 = report["resolutions"][1];
  EXPECT_EQ(r512["resolution"].get<uint32_t>(), 512u);
  EXPECT_EQ(r512["mmh_bytes"].get<uint64_t>(), inspected["mmh"]["payload_bytes"].get<uint64_t>());
  ASSERT_EQ(r512["points"].size(), 4u);
  bool found = false;
  for (const auto& p : r512["points"]) {
    EXPECT_GT(p["bytes"].get<uint64_t>(), 0u);
    EXPECT_NEAR(p["ratio_vs_mmh"].get<double>(),
                double(p["bytes"].get<uint64_t>()) / double(r512["mmh_bytes"].get<uint64_t>()), 1e-9);
    EXPECT_GT(p["point_random_per_second"].get<double>(), 0.0);
    EXPECT_GT(p["pcf3_random_per_second"].get<double>(), 0.0);
    if (p["treelet_height"] == 4 && p["chunk_size"] == 32) {
      found = true;
      EXPECT_EQ(p["bytes"].get<uint64_t>(), inspected["dagmh"]["payload_bytes"].get<uint64_t>());
    }
  }
  EXPECT_TRUE(found);
  const auto& shared = r512["shared_dictionary"];
  EXPECT_LE(shared["shared_nodes"].get<uint64_t>(), shared["per_tile_nodes"].get<uint64_t>());
  EXPECT_EQ(shared["saving_bytes"].get<int64_t>(),
            int64_t(shared["per_tile_topology_bytes"].get<uint64_t>()) -
                int64_t(shared["dictionary_bytes"].get<uint64_t>() + shared["root_ref_bytes"].get<uint64_t>()));

  // Bad parameters are refused.
  output.clear();
  EXPECT_EQ(testing::run_command(testing::cli_path().string() + " dagmh-study " + scene + " -r 256 --heights 7 2>&1",
                                 &output),
            2)
      << output;
}

// Under the surfaces contract the study renders what a surfaces build stores, and its value classes
// add up to DAG-MH's value count.
TEST(DagMhStudy, SurfacesContractMatchesASurfacesBuildAndCountsEveryValue) {
  testing::TempDir dir;
  const std::string scene = testing::shared_scene("fzk_haus/fzk_haus.obj").string();
  const std::string store = (dir.path() / "s").string();
  std::string output;
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " build " + scene +
                                     " --up y -r 512 --tile 256 -m dagmh,cpvs --receivers surfaces -q --out " + store,
                                 &output),
            0)
      << output;
  output.clear();
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " inspect --json " + store + " 2>/dev/null", &output), 0)
      << output;
  const auto dagmh = nlohmann::json::parse(output)["methods"]["dagmh"];
  const auto cpvs = nlohmann::json::parse(output)["methods"]["cpvs"];
  output.clear();
  ASSERT_EQ(testing::run_command(testing::cli_path().string() + " dagmh-study " + scene +
                                     " --up y -r 512 --tile 256 --heights 4 --chunks 32 --lookups 100 --receivers surfaces"
                                     " --json -q 2>/dev/null",
                                 &output),
            0)
      << output;
  const auto r512 = nlohmann::json::parse(output)["resolutions"][0];
  ASSERT_EQ(r512["points"].size(), 1u);
  EXPECT_EQ(r512["points"][0]["bytes"].get<uint64_t>(), dagmh["payload_bytes"].get<uint64_t>());
  // The peer DAG-MH is compared with, from the same intervals.
  EXPECT_EQ(r512["cpvs_bytes"].get<uint64_t>(), cpvs["payload_bytes"].get<uint64_t>());
  const auto& values = r512["mh_values"];
  const uint64_t zero = values["zero_width"], narrow = values["narrow"], wide = values["wide"], miss = values["miss"];
  EXPECT_EQ(zero + narrow + wide + miss, dagmh["dag"]["values"].get<uint64_t>());
  EXPECT_GT(zero, 0u) << "fzk_haus has thin layers: some intervals have zero width under surfaces";
  EXPECT_GT(wide, 0u);

  output.clear();
  EXPECT_EQ(testing::run_command(testing::cli_path().string() + " dagmh-study " + scene + " -r 256 --receivers nowhere 2>&1",
                                 &output),
            2)
      << output;
}

// The entry rule (docs/receiver-contracts.md) studied on fzk_haus: under `surfaces` it widens the
// thin layers' zero-width intervals, so DAG-MH shrinks more than CPVS from the same intervals;
// under `anywhere` it does nothing.
TEST(DagMhStudy, EntryRuleWidensZeroWidthIntervalsUnderSurfacesOnly) {
  const std::string scene = testing::shared_scene("fzk_haus/fzk_haus.obj").string();
  auto study = [&](const std::string& args) {
    std::string output;
    EXPECT_EQ(testing::run_command(testing::cli_path().string() + " dagmh-study " + scene +
                                       " --up y -r 512 --tile 256 --heights 4 --chunks 32 --lookups 100 --json -q " +
                                       args + " 2>/dev/null",
                                   &output),
              0)
        << output;
    return nlohmann::json::parse(output)["resolutions"][0];
  };
  // Off by flag; on by default, as in builds (at the default bias, 2 texels).
  const auto off = study("--receivers surfaces --entry-slack-texels 0"), on = study("--receivers surfaces");
  EXPECT_LT(on["mh_values"]["zero_width"].get<uint64_t>(), off["mh_values"]["zero_width"].get<uint64_t>() / 2);
  EXPECT_LT(on["points"][0]["bytes"].get<uint64_t>(), off["points"][0]["bytes"].get<uint64_t>());
  EXPECT_LT(on["points"][0]["ratio_vs_cpvs"].get<double>(), off["points"][0]["ratio_vs_cpvs"].get<double>());
  const auto anywhere = study("--receivers anywhere"), anywhere_on = study("--receivers anywhere --entry-slack-texels 2");
  EXPECT_EQ(anywhere_on["points"][0]["bytes"], anywhere["points"][0]["bytes"]);
  EXPECT_EQ(anywhere_on["cpvs_bytes"], anywhere["cpvs_bytes"]);
}

}  // namespace
}  // namespace shadowtiles
