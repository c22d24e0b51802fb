// Sharded builds and `shadowtiles merge` (issue 16): the merge of N shard stores equals the
// one-machine build of the same config (every blob, info record, progress record and top tree
// byte-identical, meta equal except timings), mismatched, missing or overlapping shards are refused
// naming the shard, and both the shard builds and the merge resume after a kill (the merge after
// SIGKILLs at 20 random moments, issue 18).
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "builder/shard_plan.hpp"
#include "codec/store_meta.hpp"
#include "store/lmdb_store.hpp"
#include "tests/random_kills.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using testing::TempDir;
// Keys and values as strings: GCC 12 warns falsely (-Wstringop-overread) on comparing maps of
// byte vectors; std::string compares the same bytes.
using Contents = std::map<std::string, std::string>;

std::string cli() { return testing::cli_path().string(); }

std::string build_command(const std::filesystem::path& out, const std::string& extra = "") {
  return cli() + " build " + testing::shared_scene("fzk_haus/fzk_haus.obj").string() +
         " --up y --sun 135,45 --resolution 4096 --tile 512 --method raw,mh,mmh,dagmh -j 2 --out " + out.string() + " " +
         extra;
}

Contents read_all(const std::filesystem::path& dir, store::Database db) {
  store::Store::Options options;
  auto store = store::Store::open(dir, options);
  EXPECT_TRUE(store.ok()) << dir;
  Contents contents;
  if (!store.ok()) return contents;
  EXPECT_TRUE((*store)->for_each(db, {}, [&](std::span<const uint8_t> k, std::span<const uint8_t> v) {
    contents.emplace(std::string(k.begin(), k.end()), std::string(v.begin(), v.end()));
    return true;
  }).ok());
  return contents;
}

StoreMeta read_meta(const std::filesystem::path& dir) {
  Contents meta = read_all(dir, store::Database::meta);
  std::string key(kMetaBuildKey);
  EXPECT_EQ(meta.count(key), 1u) << dir;
  auto parsed = StoreMeta::parse(std::string(meta[key].begin(), meta[key].end()));
  EXPECT_TRUE(parsed.ok()) << dir;
  return parsed.ok() ? *parsed : StoreMeta{};
}

// The merged store equals the one-machine build: data byte for byte, meta except timings.
void expect_same_build(const std::filesystem::path& merged, const std::filesystem::path& single) {
  for (auto db : {store::Database::tiles, store::Database::tileinfo, store::Database::preview, store::Database::progress,
                  store::Database::top}) {
    Contents a = read_all(merged, db), b = read_all(single, db);
    EXPECT_FALSE(b.empty()) << store::database_name(db);
    EXPECT_EQ(a.size(), b.size()) << store::database_name(db);
    EXPECT_TRUE(a == b) << store::database_name(db) << " differs";
  }
  StoreMeta a = read_meta(merged), b = read_meta(single);
  EXPECT_TRUE(a.complete);
  EXPECT_FALSE(a.shard.has_value());
  auto stats_a = a.build_stats, stats_b = b.build_stats;
  for (const char* key : {"bytes_by_method", "payload_bytes_by_method", "top_bytes_by_method", "rays"})
    EXPECT_EQ(stats_a[key], stats_b[key]) << key;
  EXPECT_EQ(stats_a["tiles"]["with_triangles"], stats_b["tiles"]["with_triangles"]);
  EXPECT_EQ(stats_a["tiles"]["stored"], stats_b["tiles"]["stored"]);
  a.build_stats = b.build_stats = nlohmann::json::object();
  EXPECT_EQ(a.to_json(), b.to_json());
}

int run(const std::string& command, std::string* output = nullptr) {
  std::string text;
  int status = testing::run_command(command, &text);
  if (output) *output = text;
  return status;
}

class ShardMerge : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    ASSERT_EQ(run(build_command(dir_->path() / "single")), 0);
    for (int i = 0; i < 4; ++i) {
      auto out = dir_->path() / ("shard" + std::to_string(i));
      std::string shard = "--shard " + std::to_string(i) + "/4";
      if (i == 1) {
        // Killed after 2 tiles, then resumed by rerunning the same command.
        EXPECT_NE(run(build_command(out, shard + " --debug-kill-after-tiles 2")), 0);
        std::string log;
        ASSERT_EQ(run(build_command(out, shard), &log), 0) << log;
        EXPECT_NE(log.find("already committed"), std::string::npos);
      } else {
        ASSERT_EQ(run(build_command(out, shard)), 0);
      }
    }
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::filesystem::path shard(int i) { return dir_->path() / ("shard" + std::to_string(i)); }
  static std::string shards() {
    std::string list;
    for (int i : {2, 0, 3, 1}) list += shard(i).string() + " ";  // any order
    return list;
  }
  static TempDir* dir_;
};
TempDir* ShardMerge::dir_ = nullptr;

TEST_F(ShardMerge, ShardsHoldDisjointSharesRecordingTheWholeBuild) {
  StoreMeta single = read_meta(dir_->path() / "single");
  uint64_t tiles = 0, begin = 0;
  for (int i = 0; i < 4; ++i) {
    StoreMeta meta = read_meta(shard(i));
    EXPECT_EQ(meta.config_hash, single.config_hash);
    EXPECT_FALSE(meta.complete);  // a share alone answers wrongly elsewhere: never served
    ASSERT_TRUE(meta.shard.has_value());
    EXPECT_EQ(meta.shard->index, uint32_t(i));
    EXPECT_TRUE(meta.shard->complete);
    EXPECT_EQ(meta.shard->morton_begin, begin);
    begin = meta.shard->morton_end;
    tiles += meta.shard->tiles;
    EXPECT_GT(meta.shard->tiles, 0u);
    EXPECT_TRUE(read_all(shard(i), store::Database::top).empty());
  }
  EXPECT_EQ(begin, 64u);
  EXPECT_EQ(tiles, single.build_stats["tiles"]["with_triangles"].get<uint64_t>());
}

// The plan weighs each tile's estimated hit texels (builder/tile_coverage_estimate.hpp); the estimate
// sampled on a 32² grid per tile must track what the build's rays then hit.
TEST_F(ShardMerge, PlanCoverageEstimateTracksTheHitTexels) {
  StoreMeta single = read_meta(dir_->path() / "single");
  std::string plan_text;
  // In a subshell, so the log on stderr stays out of the JSON (run() appends 2>&1). Appended piece
  // by piece: GCC 12 warns falsely (-Wrestrict) on "(" + std::string.
  std::string command = cli();
  command.insert(0, 1, '(');
  command += " build " + testing::shared_scene("fzk_haus/fzk_haus.obj").string();
  command += " --up y --sun 135,45 --resolution 4096 --tile 512 --method raw,mh,mmh,dagmh --plan-shards 4 2>/dev/null)";
  ASSERT_EQ(run(command, &plan_text), 0) << plan_text;
  auto plan = nlohmann::json::parse(plan_text);
  double estimate = plan["covered_texels_estimate"].get<double>();
  double hits = single.build_stats["hit_texels"].get<double>();
  ASSERT_GT(hits, 0);
  EXPECT_NEAR(estimate / hits, 1.0, 0.1) << "estimate " << estimate << " hit texels " << hits;
  EXPECT_LE(plan["imbalance"].get<double>(), 1.1);
}

// Every shard process computes the plan itself, so the plan (with the coarse depth map behind its
// work model, builder/tile_coverage_estimate.hpp) must come out identical in every process; and
// `--tile-costs` reports a measured cost for every tile a build renders, to check the model against.
TEST_F(ShardMerge, PlanIsIdenticalInEveryProcessAndTileCostsCoverEveryTile) {
  std::string command = cli();
  command.insert(0, 1, '(');
  command += " build " + testing::shared_scene("fzk_haus/fzk_haus.obj").string();
  command += " --up y --sun 135,45 --resolution 4096 --tile 512 --method raw,mh,mmh,dagmh --plan-shards 4 --tile-costs 2>/dev/null)";
  std::string first, second;
  ASSERT_EQ(run(command, &first), 0) << first;
  ASSERT_EQ(run(command, &second), 0) << second;
  auto plan = nlohmann::json::parse(first);
  EXPECT_EQ(plan, nlohmann::json::parse(second));
  ASSERT_EQ(plan["tile_work"].size(), plan["tiles"]["with_triangles"].get<size_t>());
  uint64_t edges = 0;
  for (const auto& t : plan["tile_work"]) {
    EXPECT_LE(t["visible_triangles"].get<uint64_t>(), t["triangle_refs"].get<uint64_t>());
    EXPECT_LE(t["triangle_edges"].get<uint64_t>(), 2u * 32 * 31);
    edges += t["triangle_edges"].get<uint64_t>();
  }
  EXPECT_GT(edges, 0u);  // a house seen by a 45° sun: walls and roofs meet inside tiles

  auto out = dir_->path() / "costs";
  std::string built;
  std::string build = build_command(out, "--shard 2/4 --json --tile-costs");
  build.insert(0, 1, '(');  // piece by piece: GCC 12 warns falsely (-Wrestrict) on "(" + std::string
  build += " 2>/dev/null)";
  ASSERT_EQ(run(build, &built), 0) << built;
  auto summary = nlohmann::json::parse(built);
  ASSERT_EQ(summary["tile_costs"].size(), summary["tiles"]["rendered"].get<size_t>());
  uint64_t hits = 0;
  std::map<std::string, double> phases;  // per-tile phase seconds, summed
  for (const auto& c : summary["tile_costs"]) {
    EXPECT_GT(c["cpu_seconds"].get<double>(), 0);
    for (const auto& [phase, seconds] : c["seconds"].items()) {
      EXPECT_GE(seconds.get<double>(), 0) << phase;
      phases[phase] += seconds.get<double>();
    }
    if (c["hit_texels"].get<uint64_t>() > 0) {
      EXPECT_GT(c["triangles"].get<uint64_t>(), 0u);
    }
    EXPECT_GE(c["morton"].get<uint64_t>(), summary["shard"]["morton_begin"].get<uint64_t>());
    EXPECT_LT(c["morton"].get<uint64_t>(), summary["shard"]["morton_end"].get<uint64_t>());
    hits += c["hit_texels"].get<uint64_t>();
  }
  EXPECT_EQ(hits, summary["hit_texels"].get<uint64_t>());
  // The tiles' phases add up to the build's (the same clocks, per tile instead of per worker).
  const auto& seconds = summary["seconds"];
  for (const auto& [phase, total] : std::map<std::string, std::string>{
           {"bvh", "bvh_thread_sum"}, {"rays", "rays_thread_sum"}, {"entry_rule", "entry_rule_thread_sum"},
           {"caps", "caps_thread_sum"}, {"encode", "encode_thread_sum"}})
    EXPECT_NEAR(phases[phase], seconds[total].get<double>(), 1e-6 + 1e-9 * phases[phase]) << phase;
  EXPECT_GT(phases["rays"], 0);
  EXPECT_FALSE(read_meta(out).build_stats.contains("tile_costs"));  // the meta stays small
}

TEST_F(ShardMerge, MergeEqualsTheOneMachineBuild) {
  auto out = dir_->path() / "merged";
  std::string log;
  ASSERT_EQ(run(cli() + " merge " + shards() + "--out " + out.string(), &log), 0) << log;
  expect_same_build(out, dir_->path() / "single");
  // Each share's record of what its rays ran on is kept, in shard order.
  const nlohmann::json embree = read_meta(out).build_stats["embree_by_shard"];
  ASSERT_EQ(embree.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(embree[size_t(i)], read_meta(shard(i)).build_stats["embree"]) << i;
  EXPECT_TRUE(embree[0].contains("version"));
  // Merging again into the complete store is a no-op.
  ASSERT_EQ(run(cli() + " merge " + shards() + "--out " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find("already holds"), std::string::npos) << log;
  // The merged store answers like the one-machine build (verify re-renders every tile).
  ASSERT_EQ(run(cli() + " verify " + out.string() + " --method mmh", &log), 0) << log;
}

TEST_F(ShardMerge, KilledMergeResumes) {
  auto out = dir_->path() / "resumed";
  EXPECT_NE(run(cli() + " merge " + shards() + "--out " + out.string() +
                " --transaction-mib 1 --debug-kill-after-transactions 2"),
            0);
  auto partial = read_all(out, store::Database::tiles);
  EXPECT_FALSE(partial.empty());
  std::string log;
  ASSERT_EQ(run(cli() + " merge " + shards() + "--out " + out.string() + " --json", &log), 0) << log;
  EXPECT_NE(log.find("\"resumed\": true"), std::string::npos) << log;
  expect_same_build(out, dir_->path() / "single");
}

// Like the build's SIGKILL test (tests/test_faults.cpp): kills at random moments of fresh and resumed
// merges, small transactions so kills land between commits; every completed round equals the
// one-machine build, and the last one is resumed to the end. Runs go on past 20 kills while fewer than
// 3 landed between commits (process start-up takes a larger share on a loaded machine).
TEST_F(ShardMerge, SigkillAtTwentyRandomMomentsThenResumeEqualsTheOneMachineBuild) {
  using Clock = std::chrono::steady_clock;
  const auto log = dir_->path() / "merge-kills.log";
  auto merge_args = [&](const std::filesystem::path& out) {
    std::vector<std::string> args{cli(), "merge"};
    for (int i : {0, 1, 2, 3}) args.push_back(shard(i).string());
    for (const char* a : {"--transaction-mib", "1", "--out"}) args.push_back(a);
    args.push_back(out.string());
    return args;
  };
  const auto start = Clock::now();
  ASSERT_EQ(testing::wait_status(testing::spawn_process(merge_args(dir_->path() / "merge-clean"), log)), 0)
      << "see " << log;
  const double clean_s = std::chrono::duration<double>(Clock::now() - start).count();
  const size_t clean_tiles = read_all(dir_->path() / "single", store::Database::tiles).size();
  auto round_dir = [&](int round) { return dir_->path() / ("merge-killed-" + std::to_string(round)); };
  const testing::RandomKillTally tally = testing::kill_at_random_moments(
      {.max_moment_s = clean_s, .kills = 20, .between_commits = 3, .seed = 16},
      [&](int round) { return merge_args(round_dir(round)); }, log,
      [&](int round) { expect_same_build(round_dir(round), dir_->path() / "single"); },
      [&](int round) { return testing::committed_tiles(round_dir(round)); },
      clean_tiles);
  const int kills = tally.kills, mid_merge_kills = tally.between_commits, runs = tally.runs,
            completed_rounds = tally.completed_rounds;
  std::printf("merge SIGKILL: %d kills (%d between commits) over %d runs, %d rounds completed and checked, clean "
              "merge %.2f s, %zu tiles\n",
              kills, mid_merge_kills, runs, completed_rounds, clean_s, clean_tiles);
}

TEST_F(ShardMerge, MissingDuplicateOrForeignShardsAreRefusedNamingTheShard) {
  auto out = dir_->path() / "refused";
  std::string log;
  EXPECT_EQ(run(cli() + " merge " + shard(0).string() + " " + shard(1).string() + " " + shard(3).string() +
                    " --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("shard 2/4 is missing"), std::string::npos) << log;
  EXPECT_EQ(run(cli() + " merge " + shards() + shard(0).string() + " --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("are both shard 0/4"), std::string::npos) << log;
  EXPECT_NE(log.find(shard(0).string()), std::string::npos) << log;
  // A share of another build (other sun): named, with both build ids.
  auto foreign = dir_->path() / "foreign";
  ASSERT_EQ(run(cli() + " build " + testing::shared_scene("fzk_haus/fzk_haus.obj").string() +
                " --up y --sun 90,30 --resolution 4096 --tile 512 --method raw,mh,mmh,dagmh --shard 2/4 --out " +
                foreign.string()), 0);
  EXPECT_EQ(run(cli() + " merge " + shard(0).string() + " " + shard(1).string() + " " + foreign.string() + " " +
                    shard(3).string() + " --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("different builds"), std::string::npos) << log;
  EXPECT_NE(log.find(foreign.string()), std::string::npos) << log;
  // A whole build is not a shard; an unfinished shard is refused.
  EXPECT_EQ(run(cli() + " merge " + (dir_->path() / "single").string() + " --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("not a shard store"), std::string::npos) << log;
  auto unfinished = dir_->path() / "unfinished";
  EXPECT_NE(run(build_command(unfinished, "--shard 2/4 --debug-kill-after-tiles 1")), 0);
  EXPECT_EQ(run(cli() + " merge " + shard(0).string() + " " + shard(1).string() + " " + unfinished.string() + " " +
                    shard(3).string() + " --out " + out.string(), &log), 2);
  EXPECT_NE(log.find("is not finished"), std::string::npos) << log;
  // A shard store is resumed only by its own share.
  EXPECT_EQ(run(build_command(shard(0), "--shard 1/4"), &log), 2);
  EXPECT_NE(log.find("holds shard 0/4 of this build"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(out / "data.mdb") && !read_all(out, store::Database::tiles).empty());
}

TEST(ShardPlan, RangesTileTheMapAndEachShareIsWithinOneTileOfIdeal) {
  std::vector<TileWork> tiles;
  uint64_t refs_seed = 1;
  for (uint64_t m = 0; m < 1024; m += 1 + (m % 7 == 0 ? 5 : 0)) {
    refs_seed = refs_seed * 6364136223846793005ull + 1442695040888963407ull;
    tiles.push_back({m, 65536, (refs_seed >> 40) % 20000});
  }
  for (uint32_t n : {1u, 2u, 3u, 4u, 7u, 16u}) {
    auto plan = plan_shards(tiles, 1024, n);
    ASSERT_EQ(plan.size(), n);
    EXPECT_EQ(plan.front().morton_begin, 0u);
    EXPECT_EQ(plan.back().morton_end, 1024u);
    double total = 0, most_tile = 0;
    for (const auto& t : tiles) { total += t.work(); most_tile = std::max(most_tile, t.work()); }
    uint64_t count = 0;
    for (uint32_t s = 0; s < n; ++s) {
      if (s) { EXPECT_EQ(plan[s].morton_begin, plan[s - 1].morton_end); }
      uint64_t inside = 0;
      for (const auto& t : tiles) inside += t.morton_index >= plan[s].morton_begin && t.morton_index < plan[s].morton_end;
      EXPECT_EQ(inside, plan[s].tiles);
      count += inside;
      EXPECT_LE(std::abs(plan[s].work - total / n), most_tile + 1e-6) << "shard " << s << " of " << n;
    }
    EXPECT_EQ(count, tiles.size());
  }
  // More shards than tiles: empty shares, still a tiling.
  auto sparse = plan_shards(std::span(tiles).first(2), 1024, 5);
  EXPECT_EQ(sparse.back().morton_end, 1024u);
  for (uint32_t s = 1; s < 5; ++s) EXPECT_EQ(sparse[s].morton_begin, sparse[s - 1].morton_end);
}

TEST(ShardPlan, ParsesIndexOverCount) {
  auto spec = parse_shard_spec("3/16");
  ASSERT_TRUE(spec.ok());
  EXPECT_EQ(spec->index, 3u);
  EXPECT_EQ(spec->count, 16u);
  for (const char* bad : {"4/4", "1", "/4", "1/", "-1/4", "1/0", "a/b", "1/4x", "0/70000"})
    EXPECT_FALSE(parse_shard_spec(bad).ok()) << bad;
}

}  // namespace
}  // namespace shadowtiles
