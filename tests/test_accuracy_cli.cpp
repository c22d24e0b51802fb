// `shadowtiles accuracy`: the error counts bench/build_sizes.py --accuracy puts in the two-contract
// table. A square roof over a ground square, lit from above: the ground under the roof is in
// shadow, so ground truth has both answers; the lossless methods answer as raw does; a scene that
// is not the store's is refused.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using testing::TempDir;

// Ground 20 x 20 at z = 0, roof 8 x 8 at z = 5 over its centre (both two-sided quads as triangles).
const std::string kRoofOverGround =
    "v -10 -10 0\nv 10 -10 0\nv 10 10 0\nv -10 10 0\n"
    "v -4 -4 5\nv 4 -4 5\nv 4 4 5\nv -4 4 5\n"
    "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n";

struct CliRun {
  int code = -1;
  std::string output;
};

CliRun run(const std::string& args) {
  CliRun r;
  r.code = testing::run_command(testing::cli_path().string() + " -q " + args, &r.output);
  return r;
}

TEST(AccuracyCommand, CountsEveryMethodAgainstGroundTruth) {
  TempDir dir;
  const auto scene = dir.path() / "roof.obj", store = dir.path() / "store";
  std::ofstream(scene) << kRoofOverGround;
  for (const char* contract : {"anywhere", "surfaces"}) {
    SCOPED_TRACE(contract);
    CliRun built = run("build " + scene.string() + " --out " + store.string() +
                    " --overwrite -r 256 --tile 128 -m raw,mh,dagmh --sun 135,60 --receivers " + contract);
    ASSERT_EQ(built.code, 0) << built.output;
    CliRun counted = run("accuracy " + store.string() + " " + scene.string() + " --receivers 4000 --json");
    ASSERT_EQ(counted.code, 0) << counted.output;
    const auto json = nlohmann::json::parse(counted.output.substr(counted.output.find('{')));
    EXPECT_EQ(json["receivers"], 4000);
    EXPECT_EQ(json["contract"], contract);
    const auto& raw = json["methods"]["raw"];
    // Truth has both answers: the roof and most of the ground are lit, the ground under the roof not.
    EXPECT_GT(raw["truth_lit"].get<uint64_t>(), 2000u);
    EXPECT_LT(raw["truth_lit"].get<uint64_t>(), 3900u);
    // A map of 256^2 gets this scene nearly right: errors only along the shadow's edge.
    EXPECT_LT(raw["false_lit"].get<uint64_t>() + raw["false_shadowed"].get<uint64_t>(), 200u);
    for (const char* method : {"mh", "dagmh"}) {
      const auto& m = json["methods"][method];
      EXPECT_EQ(m["false_lit"], raw["false_lit"]) << method;
      EXPECT_EQ(m["differs_from_raw"], 0) << method;
    }
  }
}

TEST(AccuracyCommand, RefusesAnotherScene) {
  TempDir dir;
  const auto scene = dir.path() / "roof.obj", other = dir.path() / "other.obj", store = dir.path() / "store";
  std::ofstream(scene) << kRoofOverGround;
  std::ofstream(other) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  ASSERT_EQ(run("build " + scene.string() + " --out " + store.string() + " -r 64 -m raw").code, 0);
  CliRun refused = run("accuracy " + store.string() + " " + other.string());
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_NE(refused.output.find("not the store's scene"), std::string::npos) << refused.output;
}

// --list-worse names exactly the receivers counted as worse than raw (point_accuracy's own list).
// The papers' texel-centre intervals (--no-exit-caps) under a grazing sun light ground just past the
// roof's shadow edge off the texel centre, where raw (the centre's own depth) shadows it: leaks the
// list must show.
TEST(AccuracyCommand, ListsTheReceiversWorseThanRaw) {
  TempDir dir;
  const auto scene = dir.path() / "roof.obj", store = dir.path() / "store";
  std::ofstream(scene) << kRoofOverGround;
  CliRun built = run("build " + scene.string() + " --out " + store.string() +
                     " -r 64 --tile 64 -m raw,mh,dagmh --sun 135,20 --receivers surfaces --no-exit-caps");
  ASSERT_EQ(built.code, 0) << built.output;
  CliRun counted = run("accuracy " + store.string() + " " + scene.string() + " --receivers 4000 --json --list-worse");
  ASSERT_EQ(counted.code, 0) << counted.output;
  const auto json = nlohmann::json::parse(counted.output.substr(counted.output.find('{')));
  EXPECT_FALSE(json["methods"]["raw"].contains("worse"));
  for (const char* method : {"mh", "dagmh"}) {
    const auto& m = json["methods"][method];
    ASSERT_TRUE(m.contains("worse")) << method;
    EXPECT_GT(m["worse_than_raw"].get<size_t>(), 0u) << method;
    EXPECT_EQ(m["worse"].size(), m["worse_than_raw"].get<size_t>()) << method;
    for (const auto& w : m["worse"]) {
      EXPECT_EQ(w["mesh_kind"], "open");
      EXPECT_EQ(w["lit"], true) << w.dump();  // this scene's worse answers are leaks
      EXPECT_EQ(w["inside_nearly_closed"], nlohmann::json::array());  // no mesh here is accepted as a solid
      EXPECT_LT(w["texel"][0].get<uint32_t>(), 64u);
      // Lit by a stored value deeper than the receiver less the bias, where raw's is shallower.
      EXPECT_GT(w["value"].get<double>(), w["raw_value"].get<double>()) << w.dump();
      EXPECT_GT(w["depth"].get<double>(), w["raw_value"].get<double>()) << w.dump();
    }
  }
  // Without the flag no list is printed.
  CliRun plain = run("accuracy " + store.string() + " " + scene.string() + " --receivers 4000 --json");
  ASSERT_EQ(plain.code, 0) << plain.output;
  EXPECT_FALSE(nlohmann::json::parse(plain.output.substr(plain.output.find('{')))["methods"]["mh"].contains("worse"));
}

}  // namespace
}  // namespace shadowtiles
