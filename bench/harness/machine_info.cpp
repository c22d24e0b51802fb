#include "bench/harness/machine_info.hpp"

#include <array>
#include <cstdio>
#include <ctime>
#include <fmt/format.h>
#include <fstream>
#include <string>
#include <thread>

namespace shadowtiles::bench {
namespace {

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  size_t start = s.find_first_not_of(" \t");
  return start == std::string::npos ? "" : s.substr(start);
}

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return out;
  std::array<char, 256> buffer;
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  ::pclose(pipe);
  return trim(out);
}

// "key : value" lines of a /proc file.
std::string proc_field(const char* file, const std::string& key) {
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key, 0) == 0) {
      size_t colon = line.find(':');
      if (colon != std::string::npos) return trim(line.substr(colon + 1));
    }
  return "";
}

std::string quoted(const std::filesystem::path& p) {
  std::string s = "'";
  for (char c : p.string()) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return s + "'";
}

}  // namespace

nlohmann::json machine_info(const std::filesystem::path& repo_dir) {
  std::string model = proc_field("/proc/cpuinfo", "model name");
  std::string mem = proc_field("/proc/meminfo", "MemTotal");  // "24576000 kB"
  double mem_gib = mem.empty() ? 0.0 : std::stod(mem) / (1024.0 * 1024.0);
  char date[32];
  std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  std::string dir = quoted(repo_dir);
  // fmt and no short-literal assignment: GCC 12 reports false -Wrestrict on string operator+ and `= "."`.
  std::string commit = run(fmt::format("git -C {} rev-parse --short=12 HEAD 2>/dev/null", dir));
  if (commit.empty()) {  // the config may live outside the work tree: try the working directory
    dir.assign(1, '.');
    commit = run("git rev-parse --short=12 HEAD 2>/dev/null");
  }
  bool dirty = !run(fmt::format("git -C {} status --porcelain --untracked-files=no 2>/dev/null", dir)).empty();
  return {{"nproc", std::thread::hardware_concurrency()},
          {"cpu_model", model.empty() ? "unknown" : model},
          {"memory_gib", mem_gib},
          {"date", date},
          {"git_commit", commit.empty() ? "unknown" : commit},
          {"git_dirty", dirty}};
}

double peak_rss_mib() {
  std::string hwm = proc_field("/proc/self/status", "VmHWM");  // "123456 kB"
  return hwm.empty() ? 0.0 : std::stod(hwm) / 1024.0;
}

double current_rss_mib() {
  std::string rss = proc_field("/proc/self/status", "VmRSS");
  return rss.empty() ? 0.0 : std::stod(rss) / 1024.0;
}

bool reset_peak_rss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return bool(out);
}

}  // namespace shadowtiles::bench
