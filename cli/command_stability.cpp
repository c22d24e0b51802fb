// `shadowtiles stability`: placeholder registration; the command is being built.
#include <spdlog/spdlog.h>

#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {

void add_stability_command(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("stability", "Run the stability scenarios and write STABILITY.md (issue #8)");
  cmd->callback([&exit_code] {
    spdlog::error("'stability' is not built yet");
    exit_code = kFailure;
  });
}

}  // namespace shadowtiles::cli
