// Helpers shared by the test executables: where the shared scenes and the CLI are, temp dirs.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace shadowtiles::testing {

// ../shared/scenes/<relative> next to the repository (as CI lays it out).
std::filesystem::path shared_scene(const std::string& relative);
// A Debian assimp-testmodels file: /usr/share/assimp/models/<relative>.
std::filesystem::path assimp_model(const std::string& relative);
// The built `shadowtiles` executable.
std::filesystem::path cli_path();
// A fresh, empty directory under the system temp dir, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};
// Whole-file bytes, for fixtures: write (truncating) and read; a missing file reads as "".
void write_file(const std::filesystem::path& path, const std::string& bytes);
std::string read_file(const std::filesystem::path& path);
// Starts args[0] with args (no shell), stdout and stderr appended to `log`; returns its pid.
pid_t spawn_process(const std::vector<std::string>& args, const std::filesystem::path& log);
// waitpid's status; with WNOHANG, -1 while the process still runs.
int wait_status(pid_t pid, int options = 0);
// Runs a shell command, returns its exit status (as from waitpid, decoded) and captures stdout+stderr.
int run_command(const std::string& command, std::string* output = nullptr);

}  // namespace shadowtiles::testing
