// Stability scenarios 7 (degenerate input) through the CLI, and `shadowtiles stability` itself:
// every degenerate scene either builds and answers correctly (exit 0) or is refused with exit code 2
// and a message naming the problem; never a crash (a signal) or a hang.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using testing::TempDir;

struct Outcome {
  int code = -1;
  std::string output;
};

Outcome build(const TempDir& dir, const std::string& obj, const std::string& flags) {
  const auto scene = dir.path() / "scene.obj";
  std::ofstream(scene) << obj;
  Outcome o;
  o.code = testing::run_command(testing::cli_path().string() + " build " + scene.string() + " --out " +
                                    (dir.path() / "store").string() + " --overwrite --method raw,mh " + flags,
                                &o.output);
  return o;
}

Outcome query(const TempDir& dir, const std::string& point) {
  Outcome o;
  o.code = testing::run_command(testing::cli_path().string() + " query " + (dir.path() / "store").string() +
                                    " --method mh --point " + point + " --json",
                                &o.output);
  return o;
}

const std::string kTriangle = "v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n";

void expect_refused(const std::string& obj, const std::string& flags, const std::string& words) {
  TempDir dir;
  Outcome o = build(dir, obj, flags);
  EXPECT_EQ(o.code, 2) << flags << "\n" << o.output;
  EXPECT_NE(o.output.find(words), std::string::npos) << "message should say '" << words << "':\n" << o.output;
}

void expect_built_and_shadowed_under_the_triangle(const std::string& obj, const std::string& flags) {
  TempDir dir;
  Outcome o = build(dir, obj, flags);
  ASSERT_EQ(o.code, 0) << flags << "\n" << o.output;
  Outcome under = query(dir, "2,2,-1"), above = query(dir, "2,2,1");
  ASSERT_EQ(under.code, 0) << under.output;
  ASSERT_EQ(above.code, 0) << above.output;
  EXPECT_NE(under.output.find("\"lit\": false"), std::string::npos) << under.output;
  EXPECT_NE(above.output.find("\"lit\": true"), std::string::npos) << above.output;
}

TEST(StabilityDegenerate, EmptySceneIsRefused) {
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "--light-dir 0,0,-1 --resolution 64", "no triangles");
}

TEST(StabilityDegenerate, OnlyZeroAreaOrNonFiniteTrianglesAreRefused) {
  expect_refused("v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n", "--light-dir 0,0,-1 --resolution 64", "triangles");
  expect_refused("v nan 0 0\nv 0 inf 0\nv 0 0 -inf\nf 1 2 3\n", "--light-dir 0,0,-1 --resolution 64", "triangles");
}

TEST(StabilityDegenerate, ZeroLightDirectionAndBadResolutionsAreRefused) {
  expect_refused(kTriangle, "--light-dir 0,0,0 --resolution 64", "direction");
  expect_refused(kTriangle, "--light-dir 0,0,-1 --resolution 1000", "power of two");
  expect_refused(kTriangle, "--light-dir 0,0,-1 --resolution 2097152", "2^20");
}

TEST(StabilityDegenerate, SingleTriangleAndBadTrianglesBesideAGoodOneBuild) {
  const std::string flags = "--light-dir 0,0,-1 --resolution 64 --tile 64";
  expect_built_and_shadowed_under_the_triangle(kTriangle, flags);
  expect_built_and_shadowed_under_the_triangle(kTriangle + "v nan 0 0\nf 1 2 4\n", flags);
  expect_built_and_shadowed_under_the_triangle(kTriangle + "v inf 0 0\nf 1 2 4\n", flags);
  expect_built_and_shadowed_under_the_triangle(kTriangle + "v 5 5 5\nf 4 4 4\nf 1 2 1\n", flags);
}

TEST(StabilityDegenerate, TileLargerThanTheMapAndResolutionOneBuild) {
  expect_built_and_shadowed_under_the_triangle(kTriangle, "--light-dir 0,0,-1 --resolution 64 --tile 4096");
  TempDir dir;
  Outcome o = build(dir, kTriangle, "--light-dir 0,0,-1 --resolution 1 --tile 1");
  ASSERT_EQ(o.code, 0) << o.output;
  Outcome above = query(dir, "2,2,1");
  EXPECT_EQ(above.code, 0) << above.output;
  EXPECT_NE(above.output.find("\"lit\": true"), std::string::npos) << above.output;
}

TEST(StabilityDegenerate, LightParallelToALargePlaneBuildsAndAnswers) {
  TempDir dir;
  Outcome o = build(dir, "v -500 -500 0\nv 500 -500 0\nv 500 500 0\nv -500 500 0\nf 1 2 3\nf 1 3 4\n",
                    "--light-dir 1,0,0 --resolution 64");
  ASSERT_EQ(o.code, 0) << o.output;
  Outcome on = query(dir, "0,0,0"), above = query(dir, "0,0,5");
  EXPECT_EQ(on.code, 0) << on.output;
  ASSERT_EQ(above.code, 0) << above.output;
  EXPECT_NE(above.output.find("\"lit\": true"), std::string::npos) << "nothing lies between it and the sun";
}

// The command end to end on quick scenarios that need no large scene (the surfaces contract's rows
// use bunny, one small shared scene): the report, the JSON and every check (scenario 9: MH, MMH and
// DAG-MH leak nothing beyond raw on each of its five subjects).
TEST(StabilityCommand, WritesTheReportAndPassesItsChecks) {
  TempDir dir;
  std::string output;
  const auto report = dir.path() / "STABILITY.md", json = dir.path() / "stability.json";
  int code = testing::run_command(testing::cli_path().string() + " stability --quick --scenarios " +
                                      "degenerate_input,hash_collisions,surfaces_contract --out " + report.string() + " --json " +
                                      json.string() + " --scene-root " + testing::shared_scene("").string(),
                                  &output);
  EXPECT_EQ(code, 0) << output;
  std::stringstream md, js;
  md << std::ifstream(report).rdbuf();
  js << std::ifstream(json).rdbuf();
  EXPECT_NE(md.str().find("## 7. Degenerate input"), std::string::npos);
  EXPECT_NE(md.str().find("## 8. Hash collisions"), std::string::npos);
  EXPECT_NE(md.str().find("## 9. Surfaces receiver contract"), std::string::npos);
  auto doc = nlohmann::json::parse(js.str());
  ASSERT_EQ(doc["scenarios"].size(), 3u);
  for (const auto& scenario : doc["scenarios"]) {
    EXPECT_GT(scenario["checks"].size(), 3u);
    for (const auto& check : scenario["checks"]) EXPECT_TRUE(check["passed"].get<bool>()) << check.dump();
  }
}

}  // namespace
}  // namespace shadowtiles
