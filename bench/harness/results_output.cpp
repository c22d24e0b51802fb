#include "bench/harness/results_output.hpp"

#include <cstdio>
#include <fstream>
#include <set>

namespace shadowtiles::bench {
namespace {

std::string csv_cell(const nlohmann::ordered_json& value) {
  if (value.is_null()) return "";
  if (value.is_string()) {
    std::string s = value.get<std::string>();
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string quoted = "\"";
    for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
    return quoted + "\"";
  }
  if (value.is_number_float()) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", value.get<double>());
    return text;
  }
  return value.dump();
}

Status write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) return make_error(ErrorCode::io_error, "cannot write " + path.string());
  return {};
}

double number(const nlohmann::ordered_json& row, const std::string& key) {
  auto it = row.find(key);
  return it != row.end() && it->is_number() ? it->get<double>() : 0.0;
}

}  // namespace

std::vector<std::string> csv_columns(const nlohmann::ordered_json& rows) {
  std::vector<std::string> columns;
  std::set<std::string> seen;
  for (const auto& row : rows)
    for (auto& [key, value] : row.items())
      if (seen.insert(key).second) columns.push_back(key);
  return columns;
}

std::string to_csv(const nlohmann::ordered_json& rows) {
  std::vector<std::string> columns = csv_columns(rows);
  std::string text;
  for (size_t i = 0; i < columns.size(); ++i) text += (i ? "," : "") + columns[i];
  text += "\n";
  for (const auto& row : rows) {
    for (size_t i = 0; i < columns.size(); ++i) {
      if (i) text += ",";
      auto it = row.find(columns[i]);
      if (it != row.end()) text += csv_cell(*it);
    }
    text += "\n";
  }
  return text;
}

Status write_results(const std::filesystem::path& out_dir, const nlohmann::ordered_json& document) {
  if (Status s = write_file(out_dir / "results.json", document.dump(2) + "\n"); !s) return s;
  return write_file(out_dir / "results.csv", to_csv(document.value("rows", nlohmann::ordered_json::array())));
}

std::string format_scene_table(const std::string& scene, const nlohmann::ordered_json& rows) {
  std::string out = "scene " + scene + "\n";
  char line[512];
  std::snprintf(line, sizeof line, "%7s %-6s %12s %8s %8s %8s %7s %7s %8s %8s %8s | %8s %8s %8s %8s %8s\n", "res",
                "method", "bytes", "B/texel", "ratio", "err%", "f-lit", "f-shad", "cam err%", "pcf3 MAE", "pcf5 MAE",
                "pt rows", "pt rand", "pt cam", "pcf3 row", "pt rowx2");
  out += line;
  for (const auto& row : rows) {
    std::snprintf(line, sizeof line,
                  "%7.0f %-6s %12.0f %8.3f %8.1f %8.3f %7.0f %7.0f %8.3f %8.4f %8.4f | %8.2f %8.2f %8.2f %8.2f %8.2f\n",
                  number(row, "resolution"), row.value("method", std::string("?")).c_str(), number(row, "blob_bytes"),
                  number(row, "bytes_per_nonempty_texel"), number(row, "compression_ratio"),
                  100.0 * number(row, "error_rate"), number(row, "false_lit"), number(row, "false_shadowed"),
                  100.0 * number(row, "camera_error_rate"), number(row, "pcf3_mae"), number(row, "pcf5_mae"),
                  number(row, "lps_point_rows_t1") / 1e6, number(row, "lps_point_random_t1") / 1e6,
                  number(row, "lps_point_camera_t1") / 1e6, number(row, "lps_pcf3_rows_t1") / 1e6,
                  number(row, "lps_point_rows_t2") / 1e6);
    out += line;
  }
  out += "  (bytes at rest; B/texel per non-empty texel; ratio vs float32 map; err% / f-lit / f-shad on uniform "
         "receivers; lookup rates in M/s, 1 thread unless x2)\n";
  return out;
}

}  // namespace shadowtiles::bench
