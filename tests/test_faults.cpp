// Faults with real processes (issue 18), each checked against an uninterrupted build byte for byte:
//   - `shadowtiles build` killed by SIGKILL at 20 random moments (scene load, ray casting, encoding,
//     commits), resumed by rerunning the same command;
//   - a build into a full file system (a small tmpfs in a private mount namespace: a real ENOSPC
//     / short write, not prlimit's SIGXFSZ): exit 1 with a clear message, the store stays readable,
//     and the same command completes it once the file system has room again.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "store/lmdb_store.hpp"
#include "tests/random_kills.hpp"
#include "testing_support.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
using testing::TempDir;

// Every record a build writes per tile, and the trees merged from them (meta holds timings).
constexpr store::Database kCompared[] = {store::Database::tiles, store::Database::top, store::Database::preview,
                                         store::Database::tileinfo};

std::map<std::string, std::string> records(const std::filesystem::path& dir, store::Database db) {
  std::map<std::string, std::string> out;
  auto store = store::Store::open(dir, {store::Store::Mode::read_only});
  EXPECT_TRUE(store.ok()) << dir << ": " << (store.ok() ? "" : store.error().message);
  if (!store.ok()) return out;
  Status s = (*store)->for_each(db, {}, [&](auto key, auto value) {
    out[std::string(key.begin(), key.end())] = std::string(value.begin(), value.end());
    return true;
  });
  EXPECT_TRUE(s.ok());
  return out;
}

void expect_same_records(const std::filesystem::path& a, const std::filesystem::path& b) {
  for (store::Database db : kCompared) {
    const auto ra = records(a, db), rb = records(b, db);
    EXPECT_FALSE(ra.empty()) << store::database_name(db);
    EXPECT_TRUE(ra == rb) << store::database_name(db) << ": " << ra.size() << " records in " << a << ", "
                          << rb.size() << " in " << b;
  }
}

std::vector<std::string> build_args(const std::filesystem::path& out) {
  return {testing::cli_path().string(),
          "build",
          testing::shared_scene("terragen/RealisticTerrain.ter").string(),
          "--heightfield",
          "*",
          "-r",
          "1024",
          "--tile",
          "64",
          "-m",
          "raw,mh,mmh,dagmh",
          "-j",
          "2",
          "--out",
          out.string()};
}

std::string join(const std::vector<std::string>& args) {
  std::string s;
  for (const auto& a : args) s += (s.empty() ? "'" : " '") + a + "'";
  return s;
}

using testing::spawn_process;
using testing::wait_status;

TEST(Faults, SigkillAtTwentyRandomMomentsThenResumeStoresExactlyTheCleanBuild) {
  TempDir dir;
  const auto log = dir.path() / "build.log";
  const auto start = Clock::now();
  ASSERT_EQ(wait_status(spawn_process(build_args(dir.path() / "clean"), log)), 0) << "clean build failed, see " << log;
  const double clean_s = std::chrono::duration<double>(Clock::now() - start).count();

  // Kill moments uniform in [0, clean/2] after each start, so kills land in every phase (scene load,
  // ray casting, encoding, commits, the top-level merge) of fresh and resumed runs.
  const size_t clean_tiles = records(dir.path() / "clean", store::Database::tiles).size();
  auto round_dir = [&](int round) { return dir.path() / ("killed-" + std::to_string(round)); };
  const testing::RandomKillTally tally = testing::kill_at_random_moments(
      {.max_moment_s = clean_s / 2, .kills = 20, .between_commits = 5, .seed = 18},
      [&](int round) { return build_args(round_dir(round)); }, log,
      [&](int round) { expect_same_records(round_dir(round), dir.path() / "clean"); },
      [&](int round) { return testing::committed_tiles(round_dir(round)); },
      clean_tiles);
  const int kills = tally.kills, mid_build_kills = tally.between_commits, runs = tally.runs,
            completed_rounds = tally.completed_rounds;
  std::printf("SIGKILL: %d kills (%d between tile commits) over %d runs, %d rounds completed and checked before "
              "the final resume, clean build %.2f s\n", kills, mid_build_kills, runs, completed_rounds, clean_s);
}

TEST(Faults, DiskFullBuildExitsOneAndResumesWhenSpaceIsBack) {
  TempDir dir;
  ASSERT_EQ(wait_status(spawn_process(build_args(dir.path() / "clean"), dir.path() / "clean.log")), 0);
  const uint64_t store_bytes = std::filesystem::file_size(dir.path() / "clean" / "data.mdb");
  const uint64_t small_kib = store_bytes / 2 / 1024;  // room for about half the store

  // Mount, build, inspect, grow, resume: all inside one private mount namespace (unshare -rm maps the
  // caller to root there, so no real root is needed where user namespaces are allowed).
  const auto mnt = dir.path() / "mnt";
  std::filesystem::create_directories(mnt);
  const auto cli = testing::cli_path().string();
  const std::string script =
      "set -u; mount -t tmpfs -o size=" + std::to_string(small_kib) + "k tmpfs '" + mnt.string() +
      "' || { echo MOUNT_FAILED; exit 0; }; " + join(build_args(mnt / "s")) + " > '" +
      (dir.path() / "full.log").string() + "' 2>&1; echo \"build_rc=$?\"; '" + cli + "' inspect '" +
      (mnt / "s").string() + "' > '" + (dir.path() / "inspect.log").string() + "' 2>&1; echo \"inspect_rc=$?\"; " +
      "mount -o remount,size=" + std::to_string(store_bytes * 4 / 1024 + 65536) + "k '" + mnt.string() + "'; " +
      join(build_args(mnt / "s")) + " > '" + (dir.path() / "resume.log").string() +
      "' 2>&1; echo \"resume_rc=$?\"; cp -a '" + (mnt / "s").string() + "' '" + (dir.path() / "resumed").string() + "'";
  const auto script_file = dir.path() / "disk_full.sh";
  {
    std::ofstream out(script_file);
    out << script << "\n";
  }
  std::string output;
  testing::run_command("unshare -rm bash '" + script_file.string() + "'", &output);
  ASSERT_EQ(output.find("MOUNT_FAILED"), std::string::npos)
      << "this test needs to mount a tmpfs (root, or user namespaces for unshare -rm): " << output;
  ASSERT_NE(output.find("build_rc=1"), std::string::npos) << "a full disk must fail the build with exit 1: " << output;
  std::string full_log;
  testing::run_command("cat '" + (dir.path() / "full.log").string() + "'", &full_log);
  EXPECT_NE(full_log.find("the disk is full"), std::string::npos) << full_log;
  EXPECT_NE(full_log.find("rerun to resume"), std::string::npos) << full_log;
  std::string inspect_log;
  testing::run_command("cat '" + (dir.path() / "inspect.log").string() + "'", &inspect_log);
  EXPECT_NE(output.find("inspect_rc=0"), std::string::npos) << "the store stays readable: " << inspect_log;
  EXPECT_NE(inspect_log.find("INCOMPLETE"), std::string::npos) << inspect_log;
  ASSERT_NE(output.find("resume_rc=0"), std::string::npos) << "the resume completes once there is room: " << output;
  expect_same_records(dir.path() / "resumed", dir.path() / "clean");
}

}  // namespace
}  // namespace shadowtiles
