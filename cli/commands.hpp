// Each `shadowtiles <command>` registers itself on the app; its callback stores the exit code.
#pragma once

#include <CLI/CLI.hpp>

namespace shadowtiles::cli {

void add_build_command(CLI::App& app, int& exit_code);
void add_merge_command(CLI::App& app, int& exit_code);
void add_store_diff_command(CLI::App& app, int& exit_code);
void add_accuracy_command(CLI::App& app, int& exit_code);
void add_query_command(CLI::App& app, int& exit_code);
void add_inspect_command(CLI::App& app, int& exit_code);
void add_verify_command(CLI::App& app, int& exit_code);
void add_serve_command(CLI::App& app, int& exit_code);
void add_bench_command(CLI::App& app, int& exit_code);
void add_render_command(CLI::App& app, int& exit_code);
void add_stability_command(CLI::App& app, int& exit_code);
void add_dagmh_study_command(CLI::App& app, int& exit_code);

}  // namespace shadowtiles::cli
