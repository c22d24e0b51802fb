// SIGKILLs at random moments of a resumable command (build, merge), as the fault tests run them:
// each run of round r is `args(r)`, killed after a uniform random delay in [0, max_moment_s] unless
// it finished first. A run that completes ends its round (`check_completed(r)` checks its output and
// the next round starts from nothing); a killed run's store must hold between 0 and `complete` whole
// units (`committed(r)`, LMDB commits being atomic). Runs go on past `kills` while fewer than
// `between_commits` kills landed between commits (on a loaded machine start-up takes a larger share
// of each run). The last round is then resumed to the end and checked.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "store/lmdb_store.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles::testing {

struct RandomKillPlan {
  double max_moment_s = 1;
  int kills = 20;
  int between_commits = 5;
  unsigned seed = 1;
  int max_runs = 200;
};

struct RandomKillTally {
  int kills = 0, between_commits = 0, runs = 0, completed_rounds = 0;
};

inline RandomKillTally kill_at_random_moments(const RandomKillPlan& plan,
                                              const std::function<std::vector<std::string>(int)>& args,
                                              const std::filesystem::path& log,
                                              const std::function<void(int)>& check_completed,
                                              const std::function<size_t(int)>& committed, size_t complete) {
  std::mt19937 rng(plan.seed);
  std::uniform_real_distribution<double> moment(0.0, plan.max_moment_s);
  RandomKillTally tally;
  int round = 0;
  while ((tally.kills < plan.kills || tally.between_commits < plan.between_commits) && tally.runs < plan.max_runs) {
    ++tally.runs;
    const pid_t pid = spawn_process(args(round), log);
    std::this_thread::sleep_for(std::chrono::duration<double>(moment(rng)));
    int status = wait_status(pid, WNOHANG);
    if (status == -1) {
      EXPECT_EQ(::kill(pid, SIGKILL), 0);
      status = wait_status(pid);
    }
    if (WIFEXITED(status)) {  // finished before the kill
      EXPECT_EQ(WEXITSTATUS(status), 0) << "a run failed: see " << log;
      if (WEXITSTATUS(status) != 0) return tally;
      check_completed(round);
      ++tally.completed_rounds;
      ++round;
      continue;
    }
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    ++tally.kills;
    const size_t units = committed(round);
    EXPECT_LE(units, complete);
    if (units > 0 && units < complete) ++tally.between_commits;
  }
  EXPECT_GE(tally.kills, plan.kills);
  EXPECT_GE(tally.between_commits, plan.between_commits) << "kills must also land between commits";
  EXPECT_EQ(wait_status(spawn_process(args(round), log)), 0) << "the last resume failed: see " << log;
  check_completed(round);
  return tally;
}

// The tile records a killed run's store holds. 0 when it holds none yet: no data.mdb, or a
// data.mdb without the store's databases (a kill between creating the LMDB file and the first
// commit, which creates them). Any other failure to open it fails the test.
inline size_t committed_tiles(const std::filesystem::path& dir) {
  if (!std::filesystem::exists(dir / "data.mdb")) return 0;
  auto store = store::Store::open(dir, {store::Store::Mode::read_only});
  if (!store.ok()) {
    EXPECT_EQ(store.error().code, ErrorCode::not_found) << dir << ": " << store.error().message;
    return 0;
  }
  size_t tiles = 0;
  EXPECT_TRUE((*store)->for_each(store::Database::tiles, {}, [&](auto, auto) { return ++tiles, true; }).ok()) << dir;
  return tiles;
}

}  // namespace shadowtiles::testing
