// `shadowtiles stability [--quick] [--out STABILITY.md] [--charts DIR] [--scenarios a,b] [--json FILE]`:
// runs the stability scenarios of issue #8 (bench/harness/stability_scenarios.hpp) over every method
// the builder supports and writes STABILITY.md with a table per scenario x method and SVG charts of
// error vs sun elevation. Exit 0 when every check passes, 3 when one fails (the report is written
// either way), 2 for bad flags or a missing scene, 1 for runtime failures.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/harness/machine_info.hpp"
#include "bench/harness/stability_report.hpp"
#include "bench/harness/stability_scenarios.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {
namespace {

struct StabilityFlags {
  bool quick = false;
  std::string out = "STABILITY.md", charts, scenarios, json, scene_root = "../shared/scenes", work_dir, from_json;
  size_t receivers = 0;
};

Status write_text(const std::filesystem::path& file, const std::string& text) {
  std::error_code ec;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
  std::ofstream out(file);
  out << text;
  out.close();
  if (!out) return make_error(ErrorCode::io_error, "cannot write " + file.string());
  return {};
}

std::string machine_line() {
  nlohmann::json m = bench::machine_info(std::filesystem::current_path());
  auto text = [&](const char* key) {
    if (!m.contains(key)) return std::string("?");
    return m[key].is_string() ? m[key].get<std::string>() : m[key].dump();
  };
  return fmt::format("{}, {} hardware threads, commit {}", text("cpu_model"), text("nproc"), text("git_commit"));
}

Status write_report(const StabilityFlags& flags, const std::vector<bench::ScenarioResult>& results, double seconds);

// Re-renders the report from a --json document of an earlier run (no scenario is run).
int rerender(const StabilityFlags& flags) {
  std::ifstream in(flags.from_json);
  if (!in) { spdlog::error("cannot read {}", flags.from_json); return kInvalidInput; }
  nlohmann::json doc = nlohmann::json::parse(in, nullptr, false);
  if (doc.is_discarded()) { spdlog::error("{} is not JSON", flags.from_json); return kInvalidInput; }
  auto results = bench::stability_from_json(doc.is_object() && doc.contains("scenarios") ? doc["scenarios"] : doc);
  if (!results) { spdlog::error("{}", results.error().message); return kInvalidInput; }
  double seconds = doc.is_object() && doc.contains("seconds") ? doc["seconds"].get<double>() : 0.0;
  if (seconds == 0)
    for (const auto& r : *results) seconds += r.seconds;  // older documents carry per-scenario times only
  if (Status s = write_report(flags, *results, seconds); !s) { spdlog::error("{}", s.error().message); return kFailure; }
  return kOk;
}

int run(const StabilityFlags& flags) {
  if (!flags.from_json.empty()) return rerender(flags);
  auto start = std::chrono::steady_clock::now();
  bench::StabilityOptions options;
  options.quick = flags.quick;
  options.scene_root = flags.scene_root;
  options.receivers = flags.receivers ? flags.receivers : (flags.quick ? 5000 : 20000);
  options.work_dir = flags.work_dir.empty()
                         ? std::filesystem::temp_directory_path() / fmt::format("shadowtiles-stability-{}", ::getpid())
                         : std::filesystem::path(flags.work_dir);
  if (!std::filesystem::is_directory(options.scene_root)) {
    spdlog::error("scene folder {} not found (--scene-root)", options.scene_root.string());
    return kInvalidInput;
  }
  std::vector<bench::ScenarioEntry> chosen;
  for (const bench::ScenarioEntry& e : bench::all_scenarios())
    if (flags.scenarios.empty() || ("," + flags.scenarios + ",").find("," + std::string(e.id) + ",") != std::string::npos)
      chosen.push_back(e);
  if (chosen.empty()) {
    std::string ids;
    for (const auto& e : bench::all_scenarios()) ids += std::string(ids.empty() ? "" : ", ") + e.id;
    spdlog::error("no scenario matches '{}' (scenarios: {})", flags.scenarios, ids);
    return kInvalidInput;
  }
  bench::StabilityContext context(options);
  if (Status s = context.init(); !s) { spdlog::error("{}", s.error().message); return exit_code_for(s.error()); }

  std::vector<bench::ScenarioResult> results;
  int code = kOk;
  for (const bench::ScenarioEntry& e : chosen) {
    spdlog::info("stability: {}", e.id);
    auto scenario_start = std::chrono::steady_clock::now();
    auto result = e.run(context);
    if (!result) {
      spdlog::error("scenario {} could not run ({}): {}", e.id, error_code_name(result.error().code),
                    result.error().message);
      code = exit_code_for(result.error());
      break;
    }
    result->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - scenario_start).count();
    size_t failed = 0;
    for (const auto& c : result->checks) failed += !c.passed;
    std::printf("%-22s %3zu checks, %zu failed, %.0f s\n", e.id, result->checks.size(), failed, result->seconds);
    std::fflush(stdout);
    if (failed && code == kOk) code = kCheckFailed;
    results.push_back(std::move(*result));
  }
  std::error_code ec;
  if (flags.work_dir.empty()) std::filesystem::remove_all(options.work_dir, ec);

  // The report is written whatever happened, with what was measured.
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (Status s = write_report(flags, results, seconds); !s) {
    spdlog::error("{}", s.error().message);
    return kFailure;
  }
  return code;
}

Status write_report(const StabilityFlags& flags, const std::vector<bench::ScenarioResult>& results, double seconds) {
  const std::filesystem::path out = flags.out;
  const std::filesystem::path charts =
      flags.charts.empty() ? (out.has_parent_path() ? out.parent_path() / "docs/stability" : "docs/stability")
                           : std::filesystem::path(flags.charts);
  bench::StabilityReportInfo info;
  info.command = "shadowtiles stability" + std::string(flags.quick ? " --quick" : "") + " --out " + flags.out;
  info.machine = machine_line();
  info.chart_dir = std::filesystem::relative(charts, out.has_parent_path() ? out.parent_path() : ".").string();
  info.seconds = seconds;
  info.quick = flags.quick;
  for (const auto& r : results)
    for (const std::string& subject : bench::elevation_subjects(r.rows))
      if (Status s = write_text(charts / ("grazing_" + subject + ".svg"), bench::error_vs_elevation_svg(r.rows, subject)); !s)
        return s;
  if (Status s = write_text(out, bench::stability_markdown(results, info)); !s) return s;
  if (!flags.json.empty()) {
    nlohmann::ordered_json doc;
    doc["seconds"] = seconds;
    doc["quick"] = flags.quick;
    doc["scenarios"] = bench::stability_json(results);
    if (Status s = write_text(flags.json, doc.dump(1)); !s) return s;
  }
  std::printf("wrote %s (charts in %s)\n", out.c_str(), charts.c_str());
  return {};
}


}  // namespace

void add_stability_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<StabilityFlags>();
  CLI::App* cmd = app.add_subcommand("stability", "Run the stability scenarios and write STABILITY.md (issue #8)");
  cmd->add_flag("--quick", flags->quick, "Small resolutions and fewer cases (about a minute)");
  cmd->add_option("--out,-o", flags->out, "Report file")->capture_default_str();
  cmd->add_option("--charts", flags->charts, "Chart folder (default: docs/stability next to the report)");
  cmd->add_option("--scenarios", flags->scenarios,
                  "Only these scenarios, comma-separated (open_geometry, thin_walls, grazing_sun, tile_seams, "
                  "precision, resolution_sweep, degenerate_input, hash_collisions, surfaces_contract)");
  cmd->add_option("--json", flags->json, "Also write every figure and check as JSON");
  cmd->add_option("--scene-root", flags->scene_root, "Folder of the shared scenes")->capture_default_str();
  cmd->add_option("--receivers", flags->receivers, "Receivers per scene (default 20000, quick 5000)");
  cmd->add_option("--from-json", flags->from_json, "Re-render the report from an earlier run's --json (runs nothing)");
  cmd->add_option("--work-dir", flags->work_dir, "Keep stores and synthetic scenes here (default: a temp dir)");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
