// shadowtiles: one CLI for the whole product (build, query, inspect, ...). Exit codes: cli/exit_codes.hpp.
#include <memory>
#include <string>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "builder/builder_version.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries results (--json documents, query answers, tables) for pipes.
  // (Single-threaded here, before any logging, so swapping the default logger's sink is safe.)
  auto& sinks = spdlog::default_logger()->sinks();
  sinks.clear();
  sinks.push_back(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  CLI::App app{"shadowtiles: lossless compressed shadow maps of huge static worlds"};
  app.require_subcommand(1);
  // The package version (CMake's project version), then the builder version stamped into stores.
  app.set_version_flag("--version", std::string("shadowtiles ") + SHADOWTILES_VERSION + " (" +
                                        shadowtiles::builder_version() + ")");
  app.fallthrough();  // -v/-q work after the command name too
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "Debug logging");
  app.add_flag("-q,--quiet", quiet, "Warnings and errors only");
  int exit_code = shadowtiles::cli::kOk;
  shadowtiles::cli::add_build_command(app, exit_code);
  shadowtiles::cli::add_merge_command(app, exit_code);
  shadowtiles::cli::add_store_diff_command(app, exit_code);
  shadowtiles::cli::add_accuracy_command(app, exit_code);
  shadowtiles::cli::add_query_command(app, exit_code);
  shadowtiles::cli::add_inspect_command(app, exit_code);
  shadowtiles::cli::add_verify_command(app, exit_code);
  shadowtiles::cli::add_serve_command(app, exit_code);
  shadowtiles::cli::add_bench_command(app, exit_code);
  shadowtiles::cli::add_render_command(app, exit_code);
  shadowtiles::cli::add_stability_command(app, exit_code);
  shadowtiles::cli::add_dagmh_study_command(app, exit_code);
  app.parse_complete_callback([&] {
    spdlog::set_level(verbose ? spdlog::level::debug : quiet ? spdlog::level::warn : spdlog::level::info);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? shadowtiles::cli::kOk : shadowtiles::cli::kInvalidInput;
  }
  return exit_code;
}
