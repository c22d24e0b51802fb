// `shadowtiles dagmh-study`: placeholder registration; the command is being built.
#include <spdlog/spdlog.h>

#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {

void add_dagmh_study_command(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("dagmh-study", "DAG-MH parameter study: treelet height x chunk size (issue #4)");
  cmd->callback([&exit_code] {
    spdlog::error("'dagmh-study' is not built yet");
    exit_code = kFailure;
  });
}

}  // namespace shadowtiles::cli
