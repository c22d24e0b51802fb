// `shadowtiles bench --config config/bench-quick.json --out DIR [--scenes a,b] [--methods m,...]`:
// the speed-vs-accuracy benchmark (bench/harness/bench_runner.hpp). Prints a table per scene and
// writes DIR/results.json and DIR/results.csv; `python3 bench/make_report.py DIR/results.json`
// turns them into BENCHMARKS.md and charts.
#include <cstdio>
#include <iostream>

#include <spdlog/spdlog.h>

#include "bench/harness/bench_config.hpp"
#include "bench/harness/bench_runner.hpp"
#include "bench/harness/results_output.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {
namespace {

struct BenchFlags {
  std::string config, out, scenes, methods;
  double min_seconds = -1;
};

int run(const BenchFlags& flags) {
  auto config = bench::load_bench_config(flags.config);
  if (!config) { spdlog::error("{}", config.error().message); return exit_code_for(config.error()); }
  if (Status s = bench::filter_bench_config(*config, flags.scenes, flags.methods); !s) {
    spdlog::error("{}", s.error().message);
    return kInvalidInput;
  }
  if (flags.min_seconds >= 0) config->min_seconds = flags.min_seconds;
  std::error_code ec;
  std::filesystem::create_directories(flags.out, ec);
  if (ec) { spdlog::error("cannot create {}: {}", flags.out, ec.message()); return kFailure; }

  bench::BenchRun run;
  run.on_scene_done = [](const std::string& scene, const nlohmann::ordered_json& rows) {
    std::printf("%s\n", bench::format_scene_table(scene, rows).c_str());
    std::fflush(stdout);
  };
  // The git commit is read from the folder of the config (inside the work tree).
  auto repo = std::filesystem::absolute(flags.config).parent_path();
  Status status = bench::run_bench(*config, flags.out, repo, run);
  // Whatever was measured is written, also after a failure.
  if (Status written = bench::write_results(flags.out, run.document); !written) {
    spdlog::error("{}", written.error().message);
    return kFailure;
  }
  for (const auto& note : run.document["notes"]) std::printf("note: %s\n", note.get<std::string>().c_str());
  if (!status) {
    spdlog::error("bench failed ({}): {}", error_code_name(status.error().code), status.error().message);
    return exit_code_for(status.error());
  }
  std::printf("wrote %s/results.json and %s/results.csv\n", flags.out.c_str(), flags.out.c_str());
  return kOk;
}

}  // namespace

void add_bench_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<BenchFlags>();
  CLI::App* cmd = app.add_subcommand("bench", "Speed vs accuracy: build, size, ground-truth error, lookups/s per method");
  cmd->add_option("--config,-c", flags->config, "Bench config JSON (config/bench-quick.json, config/bench-standard.json)")
      ->required();
  cmd->add_option("--out,-o", flags->out, "Output folder (results.json, results.csv, stores/)")->required();
  cmd->add_option("--scenes", flags->scenes, "Only these scenes of the config, comma-separated");
  cmd->add_option("--methods,-m", flags->methods, "Methods to build instead of the config's (raw always included)");
  cmd->add_option("--min-seconds", flags->min_seconds, "Override the config's minimum time per lookup loop");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
