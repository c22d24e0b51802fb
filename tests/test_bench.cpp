// `shadowtiles bench` end to end on a tiny config (512^2, 2,000 receivers): results are written with
// the expected columns, sizes are positive, and the lossless methods (mh, mmh, dagmh, when the
// builder supports them) are smaller than raw and never less accurate.
//
// Tolerance of "never less accurate": a query is lit when depth - bias <= value; raw stores the
// interval's lower bound, a lossless method any value in [lower, upper]. The two answers can differ
// only for a receiver whose biased depth lies inside (lower, upper] of its texel.
// - bunny is a nearly closed solid by default (holes in its base, docs/receiver-contracts.md): its
//   texels get exits, and a lossless method is never false-lit more than raw (tolerance 0).
// - nefertiti is closed: intervals span the solid (exit pulled back 4 texels). A receiver on the
//   bust's own surface, away from the sun, whose texel-centre ray pierces the bust, can be answered
//   lit by a lossless method (raw: shadowed) near silhouettes; on sun-facing steep slopes the lossless
//   answer is the better one (raw's lower bound gives acne). Measured at 512^2: 30 of 2,000 answers
//   differ from raw's, 10 for the worse, and the total is better (57 wrong vs 67). We allow the
//   lossless error count, and the answers worse than raw's, to exceed raw's by at most 1% (20).
// Sizes: lossless < raw is asserted on the closed scene only (see the bunny note below).
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tests/testing_support.hpp"

namespace st = shadowtiles;
using st::testing::TempDir;

namespace {

using shadowtiles::testing::read_file;

const char* kLossless[] = {"mh", "mmh", "dagmh"};


struct BenchOutput {
  nlohmann::json doc;
  std::string csv;
  std::filesystem::path results;  // results.json
};

BenchOutput run_tiny_bench(const TempDir& dir) {
  nlohmann::json config = {
      {"scene_root", (st::testing::shared_scene("")).string()},
      {"methods", {"raw", "mh", "mmh", "dagmh"}},
      {"resolutions", {512}},
      {"tile_size", 256},
      {"receivers", 2000},
      {"camera", {{"width", 40}, {"height", 30}}},
      {"min_seconds", 0.02},
      {"scenes",
       {{{"name", "bunny"}, {"file", "bunny/stanford-bunny.obj"}, {"up", "y"}, {"sun", {135, 45}}},
        {{"name", "nefertiti"}, {"file", "nefertiti/nefertiti.obj"}, {"up", "z"}, {"sun", {135, 45}}}}}};
  std::ofstream(dir.path() / "tiny.json") << config.dump(2);
  std::string output;
  const auto out = dir.path() / "out";
  int code = st::testing::run_command(st::testing::cli_path().string() + " -q bench --config " +
                                          (dir.path() / "tiny.json").string() + " --out " + out.string(),
                                      &output);
  EXPECT_EQ(code, 0) << output;
  BenchOutput result;
  result.doc = nlohmann::json::parse(read_file(out / "results.json"), nullptr, false);
  result.csv = read_file(out / "results.csv");
  result.results = out / "results.json";
  // The per-scene table went to stdout.
  EXPECT_NE(output.find("scene bunny"), std::string::npos) << output;
  return result;
}

TEST(Bench, TinyRunWritesSaneFigures) {
  if (!std::filesystem::exists(st::testing::shared_scene("bunny/stanford-bunny.obj")))
    GTEST_SKIP() << "needs ../shared/scenes";
  TempDir dir;
  BenchOutput out = run_tiny_bench(dir);
  ASSERT_FALSE(out.doc.is_discarded());
  ASSERT_TRUE(out.doc.contains("rows"));

  // Machine info and CSV columns.
  for (const char* key : {"nproc", "cpu_model", "date", "git_commit"}) EXPECT_TRUE(out.doc["machine"].contains(key)) << key;
  const std::string header = out.csv.substr(0, out.csv.find('\n'));
  for (const char* column :
       {"scene", "resolution", "method", "blob_bytes", "payload_bytes", "bytes_per_nonempty_texel", "compression_ratio",
        "build_rays_s", "build_encode_s", "build_peak_rss_mib", "error_rate", "false_lit", "false_shadowed",
        "camera_error_rate", "pcf3_mae", "pcf5_mae", "lps_point_rows_t1", "lps_point_random_t2", "lps_point_camera_t1",
        "lps_pcf3_rows_t1", "lps_pcf5_random_t2"})
    EXPECT_NE(header.find(column), std::string::npos) << column << " missing from " << header;
  size_t lines = 0;
  for (char c : out.csv) lines += c == '\n';
  EXPECT_EQ(lines, out.doc["rows"].size() + 1);

  // Per scene: raw present, every figure sane, lossless methods smaller and as accurate.
  std::map<std::string, nlohmann::json> raw;
  for (const auto& row : out.doc["rows"])
    if (row["method"] == "raw") raw[row["scene"]] = row;
  ASSERT_EQ(raw.size(), 2u);
  for (const auto& row : out.doc["rows"]) {
    const std::string what = row["scene"].get<std::string>() + "/" + row["method"].get<std::string>();
    EXPECT_GT(row["blob_bytes"].get<double>(), 0) << what;
    EXPECT_GT(row["payload_bytes"].get<double>(), 0) << what;
    EXPECT_GT(row["nonempty_texels"].get<double>(), 0) << what;
    EXPECT_EQ(row["receivers"].get<int>(), 2000) << what;
    EXPECT_GT(row["camera_receivers"].get<int>(), 0) << what;
    EXPECT_GT(row["lps_point_rows_t1"].get<double>(), 0) << what;
    EXPECT_GT(row["lps_pcf5_random_t2"].get<double>(), 0) << what;
    EXPECT_LT(row["error_rate"].get<double>(), 0.2) << what;  // raw at 512^2 agrees on the vast majority
    EXPECT_GE(row["pcf3_mae"].get<double>(), 0) << what;
    EXPECT_LT(row["pcf3_mae"].get<double>(), 0.2) << what;
    EXPECT_GT(row["build_method_encode_s"].get<double>(), 0) << what;  // each method's own encode time
    // Cold starts of the first batch: local, POSTed to a fresh server, and through a streaming client
    // fetching over HTTP. All three read the same tiles (every tile with geometry: 1M surface points).
    ASSERT_TRUE(row.contains("cold_http_post_s")) << what;
    EXPECT_GT(row["cold_http_post_s"].get<double>(), 0) << what;
    EXPECT_GT(row["cold_http_stream_s"].get<double>(), 0) << what;
    EXPECT_GT(row["cold_batch_bytes_read"].get<uint64_t>(), 0u) << what;
    EXPECT_EQ(row["cold_http_stream_bytes"].get<uint64_t>(), row["cold_batch_bytes_read"].get<uint64_t>()) << what;
    EXPECT_EQ(row["cold_http_post_bytes_read"].get<uint64_t>(), row["cold_batch_bytes_read"].get<uint64_t>()) << what;
    // Then the warm HTTP batch (issue 15's 100k-point POSTs): a rate per POST, the best no lower than the median.
    ASSERT_TRUE(row.contains("http_batch_lps_median")) << what;
    EXPECT_GT(row["http_batch_points"].get<uint64_t>(), 0u) << what;
    EXPECT_LE(row["http_batch_points"].get<uint64_t>(), 100000u) << what;
    EXPECT_GT(row["http_batch_lps_median"].get<double>(), 0) << what;
    EXPECT_GE(row["http_batch_lps_best"].get<double>(), row["http_batch_lps_median"].get<double>()) << what;
    const std::string method = row["method"];
    if (std::find(std::begin(kLossless), std::end(kLossless), method) == std::end(kLossless)) continue;
    const auto& ref = raw[row["scene"]];
    const auto errors = [](const nlohmann::json& r, const char* prefix) {
      return r[std::string(prefix) + "false_lit"].get<int64_t>() + r[std::string(prefix) + "false_shadowed"].get<int64_t>();
    };
    if (row["scene"] == "bunny") {  // a nearly closed solid: no light beyond raw's
      EXPECT_LE(row["false_lit"].get<int64_t>(), ref["false_lit"].get<int64_t>()) << what;
    } else {
      EXPECT_LT(row["blob_bytes"].get<double>(), ref["blob_bytes"].get<double>()) << what << " is not smaller than raw";
      // Measured at 512^2: mh 57 wrong vs raw 67; 30 answers differ from raw's, 10 of them for the worse.
      EXPECT_LE(errors(row, ""), errors(ref, "") + 20) << what << " (1% of 2,000 receivers)";
      EXPECT_LE(row["worse_than_raw"].get<int>(), 20) << what;
    }
  }
}

// The report generator (bench/make_report.py, python3-matplotlib from scripts/install-deps.sh) turns
// two runs' results into one BENCHMARKS.md with every scene, the paper anchors and all charts.
TEST(Bench, ReportMergesRunsIntoMarkdownAndCharts) {
  if (!std::filesystem::exists(st::testing::shared_scene("bunny/stanford-bunny.obj")))
    GTEST_SKIP() << "needs ../shared/scenes";
  TempDir dir;
  BenchOutput out = run_tiny_bench(dir);
  ASSERT_FALSE(out.doc.is_discarded());
  // A second "run": the same rows at another resolution, as a separate 64K run would add.
  nlohmann::json second = out.doc;
  for (auto& row : second["rows"]) row["resolution"] = 1024;
  for (auto& build : second["builds"]) build["resolution"] = 1024;
  std::ofstream(dir.path() / "second.json") << second.dump();
  const auto md = dir.path() / "BENCH.md", charts = dir.path() / "charts";
  std::string output;
  const std::string script = (std::filesystem::path(SHADOWTILES_SOURCE_DIR) / "bench" / "make_report.py").string();
  int code = st::testing::run_command("python3 " + script + " " + out.results.string() + " " +
                                          (dir.path() / "second.json").string() + " --md " + md.string() +
                                          " --charts " + charts.string(),
                                      &output);
  ASSERT_EQ(code, 0) << output;
  const std::string text = read_file(md);
  for (const char* part : {"## bunny", "## nefertiti", "## Paper anchors", "DAG-MH/MMH", "| 1K | dagmh |",
                           "| 512 | dagmh |", "second.json"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " missing from the report";
  for (const char* chart : {"error_vs_bytes", "error_vs_speed", "bytes_vs_resolution", "build_seconds", "encode_seconds"})
    for (const char* ext : {".svg", ".png"})
      EXPECT_GT(std::filesystem::file_size(charts / (std::string(chart) + ext)), 1000u) << chart << ext;
}

// "contract" builds the scene's stores under that receiver contract and every row names it; on open
// geometry the surfaces contract is what lets the trees shrink (docs/receiver-contracts.md), and the
// surfaces block of the query report is written beside the default one.
TEST(Bench, ContractKeyBuildsUnderThatContractAndRowsNameIt) {
  if (!std::filesystem::exists(st::testing::shared_scene("fzk_haus/fzk_haus.obj")))
    GTEST_SKIP() << "needs ../shared/scenes";
  TempDir dir;
  // fzk_haus: mostly open meshes (IFC shells), few of them nearly closed solids.
  const nlohmann::json haus = {{"file", "fzk_haus/fzk_haus.obj"}, {"up", "y"}, {"sun", {135, 45}}};
  nlohmann::json anywhere = haus, surfaces = haus;
  anywhere["name"] = "haus";
  surfaces["name"] = "haus_surfaces";
  surfaces["contract"] = "surfaces";
  nlohmann::json config = {{"scene_root", (st::testing::shared_scene("")).string()},
                           {"methods", {"raw", "mh"}},
                           {"resolutions", {256}},
                           {"tile_size", 128},
                           {"receivers", 500},
                           {"camera", {{"width", 0}}},
                           {"threads", {1}},
                           {"batch_points", 20000},
                           {"min_seconds", 0.01},
                           {"scenes", {anywhere, surfaces}}};
  std::ofstream(dir.path() / "contracts.json") << config.dump(2);
  std::string output;
  const auto out = dir.path() / "out";
  ASSERT_EQ(st::testing::run_command(st::testing::cli_path().string() + " -q bench --config " +
                                         (dir.path() / "contracts.json").string() + " --out " + out.string(),
                                     &output),
            0)
      << output;
  const auto doc = nlohmann::json::parse(read_file(out / "results.json"), nullptr, false);
  ASSERT_FALSE(doc.is_discarded());
  std::map<std::string, nlohmann::json> rows;  // "scene/method"
  for (const auto& row : doc["rows"])
    rows[row["scene"].get<std::string>() + "/" + row["method"].get<std::string>()] = row;
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows["haus/mh"]["contract"], "anywhere");
  EXPECT_EQ(rows["haus_surfaces/mh"]["contract"], "surfaces");
  EXPECT_EQ(rows["haus_surfaces/raw"]["contract"], "surfaces");
  for (const auto& build : doc["builds"])
    EXPECT_EQ(build["contract"], build["scene"] == "haus" ? "anywhere" : "surfaces");
  // Zero-width intervals on the open meshes under anywhere; under surfaces the tree has room to shrink
  // (measured at 256²: 95.6 kB vs 148.2 kB; 9x for DAG-MH at 4096², BENCHMARKS.md).
  EXPECT_LT(rows["haus_surfaces/mh"]["payload_bytes"].get<double>(),
            0.8 * rows["haus/mh"]["payload_bytes"].get<double>());
  // Every receiver the bench samples lies on a surface: MH answers them as raw does.
  EXPECT_LE(rows["haus_surfaces/mh"]["false_lit"].get<int64_t>(), rows["haus_surfaces/raw"]["false_lit"].get<int64_t>());

  const auto md = dir.path() / "BENCH.md";
  std::ofstream(md) << "# Benchmarks\n\n<!-- queries:begin -->\nkept\n<!-- queries:end -->\n";
  const std::string script = (std::filesystem::path(SHADOWTILES_SOURCE_DIR) / "bench" / "query_report.py").string();
  ASSERT_EQ(st::testing::run_command("python3 " + script + " " + (out / "results.json").string() + " --md " + md.string() +
                                         " --block queries-surfaces",
                                     &output),
            0)
      << output;
  const std::string text = read_file(md);
  EXPECT_NE(text.find("<!-- queries:begin -->\nkept\n<!-- queries:end -->"), std::string::npos) << text;
  EXPECT_NE(text.find("<!-- queries-surfaces:begin -->"), std::string::npos) << text;
  EXPECT_NE(text.find("receiver contract anywhere/surfaces"), std::string::npos) << text;
}

TEST(Bench, RejectsAnUnknownContract) {
  TempDir dir;
  std::ofstream(dir.path() / "bad.json") << R"({"scenes": [{"name": "x", "file": "x.obj", "contract": "everywhere"}]})";
  std::string output;
  int code = st::testing::run_command(st::testing::cli_path().string() + " bench --config " +
                                          (dir.path() / "bad.json").string() + " --out " + (dir.path() / "o").string(),
                                      &output);
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("contract must be"), std::string::npos) << output;
}

TEST(Bench, RejectsUnknownConfigKeys) {
  TempDir dir;
  std::ofstream(dir.path() / "bad.json") << R"({"scenes": [{"name": "x", "file": "x.obj"}], "resolution": [512]})";
  std::string output;
  int code = st::testing::run_command(st::testing::cli_path().string() + " bench --config " +
                                          (dir.path() / "bad.json").string() + " --out " + (dir.path() / "o").string(),
                                      &output);
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("unknown key 'resolution'"), std::string::npos) << output;
}

}  // namespace
