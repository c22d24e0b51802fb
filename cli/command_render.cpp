// `shadowtiles render`: placeholder registration; the command is being built.
#include <spdlog/spdlog.h>

#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {

void add_render_command(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("render", "Render a frame of a scene shadowed by a store or server (issue #9)");
  cmd->callback([&exit_code] {
    spdlog::error("'render' is not built yet");
    exit_code = kFailure;
  });
}

}  // namespace shadowtiles::cli
