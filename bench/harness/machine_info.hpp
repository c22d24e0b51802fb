// MachineInfo: what a benchmark ran on, recorded beside every figure (results.json, BENCHMARKS.md):
// CPU count and model (/proc/cpuinfo), memory, date (UTC), git commit of the working tree.
// Errors: none; fields that cannot be read stay "unknown".
// Thread safety: pure function (runs `git` as a child process).
#pragma once

#include <filesystem>

#include <nlohmann/json.hpp>

namespace shadowtiles::bench {

// `repo_dir`: where to ask git for the commit (a folder inside the work tree).
nlohmann::json machine_info(const std::filesystem::path& repo_dir);

// Peak resident memory (VmHWM) of this process in MiB, and a reset of it so the next phase
// measures its own peak (Linux >= 4.0: /proc/self/clear_refs "5"). reset returns false when the
// kernel refuses (the peak then covers the process lifetime).
double peak_rss_mib();
// Resident set size now (VmRSS), MiB.
double current_rss_mib();
bool reset_peak_rss();

}  // namespace shadowtiles::bench
