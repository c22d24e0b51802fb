// `shadowtiles merge SHARD... --out STORE`: join the shard stores of a sharded build into one store.
#include <cstdio>
#include <iostream>

#include <spdlog/spdlog.h>

#include "builder/shard_merge.hpp"
#include "cli/batch_allocator.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {
namespace {

struct MergeFlags {
  std::vector<std::string> shards;
  std::string out;
  uint64_t transaction_mib = 64;
  bool overwrite = false, json = false;
  uint64_t kill_after = 0;
};

int run(const MergeFlags& flags) {
  MergeConfig config;
  for (const auto& s : flags.shards) config.shards.emplace_back(s);
  config.out = flags.out;
  if (flags.transaction_mib < 1 || flags.transaction_mib > 4096) {
    spdlog::error("--transaction-mib must be in [1, 4096]");
    return kInvalidInput;
  }
  config.transaction_bytes = flags.transaction_mib << 20;
  config.overwrite = flags.overwrite;
  config.debug_kill_after_transactions = flags.kill_after;
  config.on_progress = [](const std::string& line) { spdlog::info("{}", line); };
  keep_transaction_buffers_resident(config.transaction_bytes);  // cli/batch_allocator.hpp
  auto summary = run_merge(config);
  if (!summary) {
    spdlog::error("merge failed ({}): {}", error_code_name(summary.error().code), summary.error().message);
    return exit_code_for(summary.error());
  }
  const auto& s = summary->stats;
  if (flags.json) {
    std::cout << s.dump(2) << "\n";
  } else if (s.value("already_complete", false)) {
    std::printf("%s already holds build %s, complete\n", flags.out.c_str(), s["build_id"].get<std::string>().c_str());
  } else {
    std::printf("merged %zu shards -> %s (build %s)\n", flags.shards.size(), flags.out.c_str(),
                s["build_id"].get<std::string>().c_str());
    std::printf("  tiles: %llu with triangles, %llu stored\n", (unsigned long long)s["tiles"]["with_triangles"].get<uint64_t>(),
                (unsigned long long)s["tiles"]["stored"].get<uint64_t>());
    std::printf("  blobs copied: %.1f MB at %.0f MB/s\n", s["merge"]["blob_bytes_copied"].get<double>() / 1e6,
                s["merge"]["blob_mb_per_second"].get<double>());
    for (auto& [phase, seconds] : s["seconds"].items())
      std::printf("  seconds %-12s %.3f\n", phase.c_str(), seconds.get<double>());
    std::printf("  peak memory %.0f MiB\n", s["peak_memory_mib"].get<double>());
  }
  return kOk;
}

}  // namespace

void add_merge_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<MergeFlags>();
  CLI::App* cmd = app.add_subcommand("merge", "Join the shard stores of a sharded build (build --shard I/N) into one store");
  cmd->add_option("shards", flags->shards, "Shard store directories (all N shards of one build)")->required();
  cmd->add_option("--out,-o", flags->out, "Store directory to write (local disk)")->required();
  cmd->add_option("--transaction-mib", flags->transaction_mib, "Bytes per write transaction, MiB")->capture_default_str();
  cmd->add_flag("--overwrite", flags->overwrite, "Replace another build in --out");
  cmd->add_flag("--json", flags->json, "Print the merge summary as JSON");
  cmd->add_option("--debug-kill-after-transactions", flags->kill_after, "Test hook: SIGKILL self after N transactions")
      ->group("");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
