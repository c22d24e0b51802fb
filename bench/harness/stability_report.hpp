// STABILITY.md and its charts from the stability scenarios' results (issue #8): a table per
// scenario x method (false lit / false shadowed rates, bytes, build seconds), the scenario's extra
// tables, its checks and notes, and an SVG chart of error vs sun elevation per method.
// Thread safety: pure functions.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/harness/stability_scenarios.hpp"

namespace shadowtiles::bench {

struct StabilityReportInfo {
  std::string command;      // the command that regenerates the report
  std::string machine;      // one line: CPU, threads, commit
  std::string chart_dir;    // relative to the report, e.g. "docs/stability"
  double seconds = 0;
  bool quick = false;
};

// Chart file names are "<chart_dir>/grazing_<subject>.svg", one per subject of the grazing scenario.
std::string stability_markdown(const std::vector<ScenarioResult>& results, const StabilityReportInfo& info);
// SVG line chart of error (solid: all wrong answers, dashed: false lit) in % of receivers vs sun
// elevation, one line per method, for `subject`'s rows. Empty when there are no such rows.
std::string error_vs_elevation_svg(const std::vector<StabilityRow>& rows, const std::string& subject);
// Subjects of rows that carry an elevation (chart names).
std::vector<std::string> elevation_subjects(const std::vector<StabilityRow>& rows);
// Everything as JSON (for scripts and tests), and back (to re-render a report without re-running).
nlohmann::ordered_json stability_json(const std::vector<ScenarioResult>& results);
// Errors: invalid_input when the document is not what stability_json writes.
Result<std::vector<ScenarioResult>> stability_from_json(const nlohmann::json& doc);

}  // namespace shadowtiles::bench
